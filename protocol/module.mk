# protocol/module.mk — protocol benchmark and the libFuzzer target of the decoder.

BENCH_TARGETS += bench-protocol
BENCH_BINS += $(BUILD)/bench/proto_bench
.PHONY: bench-protocol fuzz fuzz-replay

$(BUILD)/bench/proto_bench: $(BUILD)/protocol/bench/proto_bench.o $(LINK_protocol)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

bench-protocol: $(BUILD)/bench/proto_bench
	@echo "== protocol"
	@$<

# libFuzzer needs clang; the decoder and its dependencies are compiled into the target.
FUZZ_CC ?= clang
FUZZ_SECONDS ?= 60
FUZZ_BIN := build/fuzz/fuzz_decode
FUZZ_SRC := protocol/fuzz/fuzz_decode.c protocol/proto_codec.c protocol/proto_message.c common/nc_error.c
$(FUZZ_BIN): $(FUZZ_SRC) protocol/proto.h common/nc_error.h
	@mkdir -p $(@D)
	$(FUZZ_CC) -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
	  -Icommon -Iprotocol $(PKG_CFLAGS) -o $@ $(FUZZ_SRC) $(PKG_LIBS) -lm

# Explore for FUZZ_SECONDS, adding new interesting inputs to the corpus.
fuzz: check-deps $(FUZZ_BIN)
	@mkdir -p build/fuzz/corpus
	$(FUZZ_BIN) -max_total_time=$(FUZZ_SECONDS) -max_len=4096 build/fuzz/corpus protocol/fuzz/corpus
	@echo "new inputs are in build/fuzz/corpus; copy the useful ones to protocol/fuzz/corpus"

# Run every corpus input once (CI).
fuzz-replay: check-deps $(FUZZ_BIN)
	$(FUZZ_BIN) -runs=0 protocol/fuzz/corpus

# netcouple-check: the conformance harness for participants (protocol/check/README.md).
CHECK_BIN := $(BIN)/netcouple-check
CHECK_OBJ := $(patsubst %.c,$(BUILD)/%.o,$(wildcard protocol/check/*.c))
EXTRA_BINS += $(CHECK_BIN)
programs: $(CHECK_BIN)
$(CHECK_BIN): $(CHECK_OBJ) $(LINK_protocol)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)
