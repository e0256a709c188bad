# dem_solver/module.mk — extra rules of the DEM module (included by the top-level Makefile).
#
# - tests/dem_solver/*.c and dem_solver/bench/*.c include the module's headers by name.
# - `make bench-dem`: granular settle benchmark (particle-steps per second, 1 and 2 threads,
#   scaling 5k..80k spheres; DEM_BENCH_LARGE=1 adds the larger sizes), beside LIGGGHTS when
#   the Debian package `liggghts` is installed.

$(BUILD)/tests/dem_solver/%.o: CFLAGS += -Idem_solver
$(BUILD)/dem_solver/bench/%.o: CFLAGS += -Idem_solver

BENCH_TARGETS += bench-dem
BENCH_BINS += $(BUILD)/bench/dem_bench
.PHONY: bench-dem
$(BUILD)/bench/dem_bench: $(BUILD)/dem_solver/bench/dem_bench.o $(LINK_dem_solver)
	@mkdir -p $(@D)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)
bench-dem: $(BUILD)/bench/dem_bench
	dem_solver/bench/run_bench.sh $<
