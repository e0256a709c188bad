# fem_solver/module.mk — `make bench` target of the FEM solver (included by the top Makefile).
BENCH_TARGETS += bench-fem
BENCH_BINS += $(BUILD)/bench/fem_bench
.PHONY: bench-fem
$(BUILD)/bench/fem_bench: $(BUILD)/fem_solver/bench/fem_bench.o $(LINK_fem_solver)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)
bench-fem: $(BUILD)/bench/fem_bench
	fem_solver/bench/run_bench.sh $< cases/barrier_mel/fem.json
# tests/fem_solver/test_calculix.sh writes its CalculiX input with fem_bench
tests: $(BUILD)/bench/fem_bench
