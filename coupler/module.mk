# coupler/module.mk — coupling-overhead benchmark (run by `make bench`).
BENCH_TARGETS += bench-coupler
BENCH_BINS += $(BUILD)/bench/coupler_bench
.PHONY: bench-coupler
$(BUILD)/bench/coupler_bench: $(BUILD)/coupler/bench/coupler_bench.o $(LINK_coupler)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)
bench-coupler: $(BUILD)/bench/coupler_bench $(BIN)/coupler
	$< $(BIN)
