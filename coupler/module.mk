# coupler/module.mk — coupling-overhead benchmark (run by `make bench`).
BENCH_TARGETS += bench-coupler
BENCH_BINS += $(BUILD)/bench/coupler_bench
.PHONY: bench-coupler
$(BUILD)/bench/coupler_bench: $(BUILD)/coupler/bench/coupler_bench.o $(LINK_coupler)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)
bench-coupler: $(BUILD)/bench/coupler_bench $(BIN)/coupler
	$< $(BIN)

# netcouple-set: the --set overrides of scripts/run_case.sh (coupler/set/netcouple_set.c).
SET_BIN := $(BIN)/netcouple-set
EXTRA_BINS += $(SET_BIN)
programs: $(SET_BIN)
$(SET_BIN): $(BUILD)/coupler/set/netcouple_set.o $(LINK_common)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)
