# netcouple — top-level build.
#
#   make            build bin/fem_solver, bin/dem_solver, bin/coupler and the protocol library
#   make test       install missing Debian packages (as root), build, run every test
#   make bench      benchmarks (protocol latency, FEM, DEM, coupling overhead)
#   make demo       run the default case and make its plots
#   make soak       kill and stall trials of scripts/run_case.sh at random moments (not part of
#                   make test): SOAK_TRIALS (default 100), SOAK_SEED (default random, printed),
#                   SOAK_JOBS trials at a time (default 2); failed trials stay in build/release/soak
#   make fuzz       run the libFuzzer targets of the protocol decoder and the input readers (clang)
#   make fuzz-replay   replay their corpora once (CI)
#   make install PREFIX=/usr/local
#   make SANITIZE=1 ...   the same with AddressSanitizer + UndefinedBehaviorSanitizer
#
# Layout: one folder per library/executable. Every `<module>/*.c` except `main.c` goes into
# `build/.../lib<module>.a`; `<module>/main.c` becomes `bin/<module>`; every
# `tests/<module>/test_*.c` becomes a test program linked against that module's library.

PREFIX ?= /usr/local
CC ?= cc
ifeq ($(origin CC),default)
CC := gcc
endif

ifeq ($(SANITIZE),1)
BUILD := build/sanitize
BIN := build/sanitize/bin
SAN_FLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
OPT := -O1 -g
else
BUILD := build/release
BIN := bin
SAN_FLAGS :=
OPT := -O2 -g
endif

PKGS := libzmq hdf5 libcjson
PKG_CFLAGS := $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
# HDF5 is linked from the static archive Debian's libhdf5-dev ships beside the shared library:
# the shared one brings libcurl and two dozen libraries of its own (for a remote-file driver
# netcouple does not use), and loading them took each program about 15 ms at every start, a
# tenth of a short coupled run (docs/notes/interface_jacobian.md, "Speed"). The archive's own
# dependencies come from its libhdf5.settings ("Extra libraries"), linked only where an
# object taken from it needs them (--as-needed: on Debian 12 no curl). Without the archive,
# the shared library.
HDF5_LIBDIR := $(patsubst -L%,%,$(filter -L%,$(shell pkg-config --libs-only-L hdf5 2>/dev/null)))
HDF5_ARCHIVE := $(firstword $(wildcard $(addsuffix /libhdf5.a,$(HDF5_LIBDIR))))
HDF5_EXTRA := $(shell sed -n 's/^ *Extra libraries: *//p' $(dir $(HDF5_ARCHIVE))libhdf5.settings 2>/dev/null)
HDF5_STATIC := $(HDF5_ARCHIVE) -Wl,--push-state,--as-needed $(or $(HDF5_EXTRA),-lsz -lz -ldl -lm) \
  -Wl,--pop-state
HDF5_LIBS := $(if $(HDF5_ARCHIVE),$(HDF5_STATIC),$(shell pkg-config --libs hdf5 2>/dev/null))
PKG_LIBS := $(shell pkg-config --libs libzmq libcjson 2>/dev/null) $(HDF5_LIBS)
# SuiteSparse ships no .pc file on Debian 12.
SUITESPARSE_CFLAGS := -I/usr/include/suitesparse
SUITESPARSE_LIBS := -lcholmod -lumfpack -lamd -lcolamd -lsuitesparseconfig

CFLAGS_BASE := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE $(OPT) \
  -Wall -Wextra -Werror -Wno-format-truncation -fopenmp $(SAN_FLAGS) -MMD -MP \
  -Icommon -Iprotocol $(PKG_CFLAGS) $(SUITESPARSE_CFLAGS)
CFLAGS += $(CFLAGS_BASE)
LDLIBS := $(PKG_LIBS) $(SUITESPARSE_LIBS) -llapack -lm -lpthread
LDFLAGS += -fopenmp $(SAN_FLAGS)

MODULES := common protocol fem_solver dem_solver coupler
PROGRAMS := fem_solver dem_solver coupler

.PHONY: all test run-tests bench run-bench demo soak fuzz install clean deps check-deps check-bench-deps
# The user-facing targets install missing packages first, then run a fresh make: compiler
# flags come from pkg-config when the Makefile is read, which on a new machine is before the
# packages exist.
all: check-deps
	@$(MAKE) --no-print-directory programs

# Build and run the whole test suite; the last line counts tests ("N passed, N failed").
test: check-deps
	@$(MAKE) --no-print-directory run-tests

run-tests: programs tests
	@scripts/run_tests.sh "$(BUILD)/tests" "$(BIN)"

# Runs the default case and writes its plots (scripts/demo.sh says where everything is).
demo: check-deps
	@$(MAKE) --no-print-directory programs
	@scripts/demo.sh

# Fault trials of the launcher (scripts/soak.py says what each trial does and checks).
SOAK_TRIALS ?= 100
SOAK_JOBS ?= 2
soak: check-deps
	@$(MAKE) --no-print-directory programs
	@/usr/bin/python3 scripts/soak.py --trials $(SOAK_TRIALS) --jobs $(SOAK_JOBS) --keep \
	  --bin $(BIN) --dir $(BUILD)/soak $(if $(SOAK_SEED),--seed $(SOAK_SEED))

check-deps:
	@scripts/check_deps.sh >/dev/null 2>&1 || scripts/install_deps.sh

deps:
	scripts/install_deps.sh

# ---- libraries -------------------------------------------------------------------------------
define module_rules
$(1)_SRC := $$(filter-out $(1)/main.c,$$(wildcard $(1)/*.c))
$(1)_OBJ := $$(patsubst %.c,$(BUILD)/%.o,$$($(1)_SRC))
$(BUILD)/lib$(1).a: $$($(1)_OBJ)
	@mkdir -p $$(@D)
	@rm -f $$@
	$$(AR) rcs $$@ $$^
endef
$(foreach m,$(MODULES),$(eval $(call module_rules,$(m))))

# The protocol library is self-contained for third-party solvers: it carries the error module.
PROTOCOL_LIB := $(BUILD)/libnetcouple_protocol.a
$(PROTOCOL_LIB): $(protocol_OBJ) $(BUILD)/common/nc_error.o
	@mkdir -p $(@D)
	@rm -f $@
	$(AR) rcs $@ $^

# Link order: module library, then shared ones.
LINK_common := $(BUILD)/libcommon.a
LINK_protocol := $(BUILD)/libprotocol.a $(LINK_common)
LINK_fem_solver := $(BUILD)/libfem_solver.a $(LINK_protocol)
LINK_dem_solver := $(BUILD)/libdem_solver.a $(LINK_protocol)
LINK_coupler := $(BUILD)/libcoupler.a $(LINK_protocol)

# V=1 shows full command lines.
Q := $(if $(V),,@)
$(BUILD)/%.o: %.c
	@mkdir -p $(@D)
	@$(if $(V),,echo "  CC      $<")
	$(Q)$(CC) $(CFLAGS) -c $< -o $@

# ---- programs --------------------------------------------------------------------------------
define program_rules
$(BIN)/$(1): $(BUILD)/$(1)/main.o $$(LINK_$(1))
	@mkdir -p $$(@D)
	$$(CC) $$(LDFLAGS) -o $$@ $$^ $$(LDLIBS)
endef
$(foreach p,$(PROGRAMS),$(if $(wildcard $(p)/main.c),$(eval $(call program_rules,$(p)))))
PROGRAM_BINS := $(foreach p,$(PROGRAMS),$(if $(wildcard $(p)/main.c),$(BIN)/$(p)))
.PHONY: programs tests
programs: $(PROGRAM_BINS) $(PROTOCOL_LIB)

# ---- tests -----------------------------------------------------------------------------------
# tests/<module>/test_*.c -> $(BUILD)/tests/<module>/test_*; helpers in tests/<module>/*.c
# (not test_*) are linked into every test of that module.
define test_rules
$(1)_TEST_SRC := $$(wildcard tests/$(1)/test_*.c)
$(1)_TEST_HELP := $$(patsubst %.c,$(BUILD)/%.o,$$(filter-out $$($(1)_TEST_SRC),$$(wildcard tests/$(1)/*.c)))
$(1)_TEST_BINS := $$(patsubst %.c,$(BUILD)/%,$$($(1)_TEST_SRC))
$(BUILD)/tests/$(1)/test_%: $(BUILD)/tests/$(1)/test_%.o $$($(1)_TEST_HELP) $$(LINK_$(1))
	@mkdir -p $$(@D)
	$$(CC) $$(LDFLAGS) -o $$@ $$^ $$(LDLIBS) -lcmocka
TEST_BINS += $$($(1)_TEST_BINS)
endef
TEST_BINS :=
$(foreach m,$(MODULES),$(eval $(call test_rules,$(m))))
tests: $(TEST_BINS)

# ---- fuzz targets of the input readers ------------------------------------------------------
# <module>/fuzz/fuzz_<name>.c with its seed corpus <module>/fuzz/corpus_<name>/:
#   make fuzz-<name>     explore for FUZZ_SECONDS with libFuzzer (clang), new inputs in
#                        build/fuzz/corpus_<name>
#   make fuzz-replay     every corpus input once through $(BUILD)/fuzz/replay_<name>, built with
#                        the ordinary compiler (no libFuzzer needed; ASan/UBSan with SANITIZE=1);
#                        the test suite replays them too (tests/common/test_fuzz_corpus.sh)
READER_FUZZ := fem_solver:gmsh fem_solver:fem_json dem_solver:stl dem_solver:dem_json \
  coupler:coupler_json
READER_FUZZ_REPLAY :=
FUZZ_READER_FLAGS = -g -O1 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE -fopenmp -Icommon -Iprotocol \
  $(PKG_CFLAGS) $(SUITESPARSE_CFLAGS)
define reader_fuzz_rules
$(BUILD)/$(1)/fuzz/%.o: CFLAGS += -I$(1)
$(BUILD)/fuzz/replay_$(2): $(BUILD)/$(1)/fuzz/fuzz_$(2).o $(BUILD)/common/fuzz/nc_fuzz_memfile.o \
  $(BUILD)/common/fuzz/nc_fuzz_replay.o $$(LINK_$(1))
	@mkdir -p $$(@D)
	$$(CC) $$(LDFLAGS) -o $$@ $$^ $$(LDLIBS)
build/fuzz/fuzz_$(2): $(1)/fuzz/fuzz_$(2).c common/fuzz/nc_fuzz_memfile.c \
  $$(filter-out $(1)/main.c,$$(wildcard $(1)/*.c)) $$(protocol_SRC) $$(common_SRC)
	@mkdir -p $$(@D)
	$$(FUZZ_CC) $$(FUZZ_READER_FLAGS) -I$(1) -o $$@ $$^ $$(PKG_LIBS) $$(SUITESPARSE_LIBS) -lm -lpthread
.PHONY: fuzz-$(2) fuzz-replay-$(2)
fuzz-$(2): check-deps build/fuzz/fuzz_$(2)
	@mkdir -p build/fuzz/corpus_$(2)
	build/fuzz/fuzz_$(2) -max_total_time=$$(FUZZ_SECONDS) -max_len=4096 -rss_limit_mb=2048 \
	  build/fuzz/corpus_$(2) $(1)/fuzz/corpus_$(2)
fuzz-replay-$(2): $(BUILD)/fuzz/replay_$(2)
	$(BUILD)/fuzz/replay_$(2) $(1)/fuzz/corpus_$(2)
READER_FUZZ_REPLAY += $(BUILD)/fuzz/replay_$(2)
fuzz: fuzz-$(2)
fuzz-replay: fuzz-replay-$(2)
endef
$(foreach f,$(READER_FUZZ),$(eval $(call reader_fuzz_rules,$(word 1,$(subst :, ,$(f))),$(word 2,$(subst :, ,$(f))))))
tests: $(READER_FUZZ_REPLAY)

# Per-module extra rules: each <module>/module.mk may add phony targets to BENCH_TARGETS
# (run by `make bench`) and define its own helpers (fuzz target, demo, ...).
BENCH_TARGETS :=
BENCH_BINS :=
EXTRA_BINS :=   # further programs into bin/ (installed with the others)
-include $(wildcard */module.mk)

bench: check-bench-deps
	@$(MAKE) --no-print-directory run-bench

run-bench: programs $(BENCH_TARGETS)

# Builds the benchmark programs without running them (CI checks that they still compile).
.PHONY: bench-programs
bench-programs: $(BENCH_BINS)

check-bench-deps:
	@scripts/check_deps.sh --bench >/dev/null 2>&1 || scripts/install_deps.sh --bench

# ---- install / clean -------------------------------------------------------------------------
# The Python participant module goes where Debian's /usr/bin/python3 looks for PREFIX's
# packages: PREFIX/lib/python3.X/dist-packages (on sys.path for /usr/local and /usr).
PYTHON_VERSION := $(shell /usr/bin/python3 -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null)
PYTHON_SITE ?= $(PREFIX)/lib/python$(or $(PYTHON_VERSION),3)/dist-packages
install: programs
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib $(DESTDIR)$(PREFIX)/include/netcouple
	install -m 755 $(PROGRAM_BINS) $(EXTRA_BINS) $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(PROTOCOL_LIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 protocol/proto.h protocol/proto_serve.h common/nc_error.h $(DESTDIR)$(PREFIX)/include/netcouple/
	install -d $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/share/doc/netcouple
	install -m 644 protocol/README.md $(DESTDIR)$(PREFIX)/share/doc/netcouple/protocol.md
	install -m 644 protocol/check/README.md $(DESTDIR)$(PREFIX)/share/doc/netcouple/netcouple-check.md
	install -d $(DESTDIR)$(PYTHON_SITE) $(DESTDIR)$(PREFIX)/share/doc/netcouple/examples
	install -m 644 scripts/participants/netcouple_participant.py $(DESTDIR)$(PYTHON_SITE)/
	install -m 755 scripts/participants/spring_plate.py scripts/participants/ball_dem.py $(DESTDIR)$(PREFIX)/share/doc/netcouple/examples/
	install -m 644 tests/coupler/cases/plate_ball/fem.json $(DESTDIR)$(PREFIX)/share/doc/netcouple/examples/plate.json
	install -m 644 tests/coupler/cases/plate_ball/dem.json $(DESTDIR)$(PREFIX)/share/doc/netcouple/examples/ball.json
	printf 'prefix=%s\nlibdir=$${prefix}/lib\nincludedir=$${prefix}/include/netcouple\n\nName: netcouple-protocol\nDescription: netcouple coupling protocol (ZeroMQ + JSON header + binary arrays)\nVersion: 1\nRequires: libzmq libcjson\nCflags: -I$${includedir}\nLibs: -L$${libdir} -lnetcouple_protocol -lm\n' \
	  "$(PREFIX)" > $(DESTDIR)$(PREFIX)/lib/pkgconfig/netcouple-protocol.pc

clean:
	rm -rf build bin

-include $(shell find build -name '*.d' 2>/dev/null)
