# Agglo build, run and test. `make help` lists the targets.
# MODE=release (default) or MODE=debug; NP = ranks, DECK = the deck and ARGS = its command-line
# overrides (--set group.variable=value) for `make run`.
# ARCH = the -march of a release build: native (default, this CPU) or e.g. x86-64-v3 for a build
# that runs on every AVX2 node of a mixed cluster. Use another BUILD directory per ARCH.
SHELL := /bin/bash
.DEFAULT_GOAL := help

MODE  ?= release
ARCH  ?= native
NP    ?= 2
BUILD ?= build
DECK  ?= input/default.nml
VENV  ?= .venv

FC := mpifort
CC := mpicc
MULTIARCH := $(shell gcc -print-multiarch 2>/dev/null || echo x86_64-linux-gnu)
HDF5_INC := /usr/include/hdf5/openmpi
HDF5_LIB := /usr/lib/$(MULTIARCH)/hdf5/openmpi

# -fwrapv: the random streams rely on two's-complement integer wrap-around.
COMMON_FLAGS := -fwrapv -fimplicit-none -ffree-line-length-132
ifeq ($(MODE),debug)
  MODE_FLAGS := -O0 -g -fcheck=all -ffpe-trap=invalid,zero,overflow -Wall -fbacktrace
else ifeq ($(MODE),release)
  MODE_FLAGS := -O3 -march=$(ARCH) -funroll-loops
else
  $(error MODE must be release or debug, not '$(MODE)')
endif
OBJ := $(BUILD)/obj
MOD := $(BUILD)/mod
# The fluid stencils (momentum_terms) are arithmetic-bound, not memory-bound: where the CPU has
# AVX-512 (in the ARCH the build targets), 512-bit vectors (GCC prefers 256-bit by default) make the predictor sweep about 1.6x
# faster at 128^3 (docs/studies/performance.md, Fluid). Same arithmetic per point, so the same results.
ifeq ($(MODE),release)
  ifneq ($(shell $(FC) -march=$(ARCH) -Q --help=target 2>/dev/null | grep -E '^[[:space:]]+-mavx512f[[:space:]]+\[enabled\]'),)
    STENCIL_FLAGS := -mprefer-vector-width=512
  endif
endif
FFLAGS := $(COMMON_FLAGS) $(MODE_FLAGS) -J$(MOD) -I$(MOD) -I/usr/include -I$(HDF5_INC)
CFLAGS := -O2 -I/usr/include/hypre
# Objects depend on a file holding the flags, rewritten only when they change: a BUILD directory
# built with another MODE or ARCH is rebuilt whole, never linked from a mix of both.
FLAGS_STAMP := $(BUILD)/flags.txt
BUILD_FLAGS := $(FC) $(FFLAGS) $(STENCIL_FLAGS) $(CC) $(CFLAGS)
ifneq ($(filter-out help clean deps tools-deps,$(MAKECMDGOALS)),)
  ifeq ($(findstring n,$(firstword -$(MAKEFLAGS))),)   # not under make -n
    $(shell mkdir -p $(BUILD) && { [ "$$(cat $(FLAGS_STAMP) 2>/dev/null)" = "$(BUILD_FLAGS)" ] \
              || echo "$(BUILD_FLAGS)" > $(FLAGS_STAMP); })
  endif
endif
$(FLAGS_STAMP):
	@mkdir -p $(@D) && echo "$(BUILD_FLAGS)" > $@
LIBS := -L$(HDF5_LIB) -Wl,-rpath,$(HDF5_LIB) -lhdf5_fortran -lhdf5 -lfftw3_mpi -lfftw3 -lHYPRE -llapack -lblas

SRC_DIRS := $(shell find src -type d)
SOURCES := $(shell find src -name '*.f90' | sort)
C_SOURCES := $(shell find src -name '*.c' | sort)
LIB_SOURCES := $(filter-out src/agglo.f90,$(SOURCES))
LIB_OBJECTS := $(patsubst %.f90,$(OBJ)/%.o,$(notdir $(LIB_SOURCES))) $(patsubst %.c,$(OBJ)/%.o,$(notdir $(C_SOURCES)))
# The validation cases (validation/README.md): their own library, linked into the test and bench
# programs, never into agglo or libagglo.a.
VALIDATION_DIRS := $(shell find validation -type d)
VALIDATION_SOURCES := $(shell find validation -name '*.f90' | sort)
VALIDATION_OBJECTS := $(patsubst %.f90,$(OBJ)/%.o,$(notdir $(VALIDATION_SOURCES)))
# Each library also depends on a file listing its members, rewritten only when the list changes: a
# source moved out of (or into) a library's folders rebuilds the library, never leaves it stale.
LIB_MEMBERS := $(BUILD)/libagglo.members
VALIDATION_MEMBERS := $(BUILD)/libvalidation.members
ifneq ($(filter-out help clean deps tools-deps,$(MAKECMDGOALS)),)
  ifeq ($(findstring n,$(firstword -$(MAKEFLAGS))),)   # not under make -n
    $(shell mkdir -p $(BUILD) && { [ "$$(cat $(LIB_MEMBERS) 2>/dev/null)" = "$(notdir $(LIB_OBJECTS))" ] \
              || echo "$(notdir $(LIB_OBJECTS))" > $(LIB_MEMBERS); })
    $(shell { [ "$$(cat $(VALIDATION_MEMBERS) 2>/dev/null)" = "$(notdir $(VALIDATION_OBJECTS))" ] \
              || echo "$(notdir $(VALIDATION_OBJECTS))" > $(VALIDATION_MEMBERS); })
  endif
endif
$(LIB_MEMBERS):
	@mkdir -p $(@D) && echo "$(notdir $(LIB_OBJECTS))" > $@
$(VALIDATION_MEMBERS):
	@mkdir -p $(@D) && echo "$(notdir $(VALIDATION_OBJECTS))" > $@
TEST_SOURCES := $(shell find tests -name 'test_*.f90' ! -path 'tests/framework/*' | sort)
TEST_SUPPORT := $(shell find tests -name '*.f90' \( -path 'tests/framework/*' -o ! -name 'test_*.f90' \) | sort)
TEST_DIRS := $(shell find tests -type d)
TEST_PROGRAMS := $(patsubst %.f90,$(BUILD)/tests/%,$(notdir $(TEST_SOURCES)))
TEST_SUPPORT_OBJECTS := $(patsubst %.f90,$(OBJ)/%.o,$(notdir $(TEST_SUPPORT)))
BENCH_SOURCES := $(shell find tools/bench -name 'bench_*.f90' 2>/dev/null | sort)
BENCH_PROGRAMS := $(patsubst %.f90,$(BUILD)/bench/%,$(notdir $(BENCH_SOURCES)))

vpath %.f90 $(SRC_DIRS) $(VALIDATION_DIRS) $(TEST_DIRS) tools/bench
vpath %.c $(SRC_DIRS)

DEB_PACKAGES := gfortran libopenmpi-dev openmpi-bin libfftw3-dev libfftw3-mpi-dev libhdf5-openmpi-dev \
                libhypre-dev liblapack-dev libblas-dev pkg-config hdf5-tools python3 python3-venv

export OMPI_ALLOW_RUN_AS_ROOT := 1
export OMPI_ALLOW_RUN_AS_ROOT_CONFIRM := 1
MPIRUN := mpirun --oversubscribe
# V=1 prints every compiler command; by default one short line per file.
ifeq ($(V),1)
  Q :=
else
  Q = @echo "  $(notdir $@)";
endif

.PHONY: help deps build run run-suspension test bench validate validate-decks clean tools-deps
.SECONDARY:
help: ## list the targets
	@echo "Agglo - make targets (MODE=release|debug, ARCH=native|x86-64-v3|..., BUILD=dir, NP=ranks, DECK=deck for run):"
	@grep -E '^[a-z-]+:.*## ' $(MAKEFILE_LIST) | sed -E 's/^([a-z-]+):.*## (.*)/  make \1\t\2/' | expand -t 20

deps: ## install the Debian packages Agglo needs (only those missing)
	@missing=""; for p in $(DEB_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  howto="run as root: apt-get update && apt-get install -y$$missing (then make again)"; \
	  if [ "$$(id -u)" = 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO=sudo; else \
	    echo "deps: missing Debian packages:$$missing; not root and no sudo: $$howto" >&2; exit 1; fi; \
	  echo "deps: installing$$missing$${SUDO:+ with sudo}"; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null \
	    || { echo "deps: apt-get could not install:$$missing; $$howto" >&2; exit 1; }; \
	fi

build: $(BUILD)/agglo ## build build/agglo (out of source)

$(BUILD)/agglo: $(OBJ)/agglo.o $(BUILD)/libagglo.a
	$(Q)$(FC) $(FFLAGS) -o $@ $^ $(LIBS)

$(BUILD)/libagglo.a: $(LIB_OBJECTS) $(LIB_MEMBERS)
	@rm -f $@
	$(Q)ar rcs $@ $(LIB_OBJECTS)

$(BUILD)/libvalidation.a: $(VALIDATION_OBJECTS) $(VALIDATION_MEMBERS)
	@rm -f $@
	$(Q)ar rcs $@ $(VALIDATION_OBJECTS)

$(OBJ)/%.o: %.f90 $(FLAGS_STAMP) | $(OBJ) $(MOD)
	$(Q)$(FC) $(FFLAGS) -c $< -o $@

$(OBJ)/momentum_terms.o: private FFLAGS += $(STENCIL_FLAGS)

$(OBJ)/%.o: %.c $(FLAGS_STAMP) | $(OBJ)
	$(Q)$(CC) $(CFLAGS) -c $< -o $@

$(BUILD)/tests/%: $(OBJ)/%.o $(TEST_SUPPORT_OBJECTS) $(BUILD)/libvalidation.a $(BUILD)/libagglo.a | $(BUILD)/tests
	$(Q)$(FC) $(FFLAGS) -o $@ $< $(TEST_SUPPORT_OBJECTS) $(BUILD)/libvalidation.a $(BUILD)/libagglo.a $(LIBS)

$(BUILD)/bench/%: $(OBJ)/%.o $(BUILD)/libvalidation.a $(BUILD)/libagglo.a | $(BUILD)/bench
	$(Q)$(FC) $(FFLAGS) -o $@ $< $(BUILD)/libvalidation.a $(BUILD)/libagglo.a $(LIBS)

$(OBJ) $(MOD) $(BUILD)/tests $(BUILD)/bench:
	@mkdir -p $@

# Module dependencies, generated from the sources (never maintained by hand).
$(BUILD)/deps.mk: $(SOURCES) $(VALIDATION_SOURCES) $(TEST_SOURCES) $(TEST_SUPPORT) $(BENCH_SOURCES) tools/fortran-deps.sh | $(OBJ)
	@tools/fortran-deps.sh $(OBJ) $(SOURCES) $(VALIDATION_SOURCES) $(TEST_SUPPORT) $(TEST_SOURCES) $(BENCH_SOURCES) > $@
ifneq ($(filter-out help clean deps tools-deps,$(MAKECMDGOALS)),)
include $(BUILD)/deps.mk
endif

run: deps tools-deps ## install, build, and run DECK (default input/default.nml) on NP ranks, with ARGS
	@$(MAKE) --no-print-directory build
	$(MPIRUN) -np $(NP) $(BUILD)/agglo $(DECK) $(ARGS)
	@# The default deck's picture: the flow on the plane through both needles (tools/agglo-figure8).
	@if [ "$(DECK)" = input/default.nml ] && [ -f output/default/fields.xdmf ]; then \
	  tools/agglo-figure8 output/default -o output/default/figure8.png > /dev/null && \
	  echo "picture: output/default/figure8.png (|u| on the plane through both needles, latest snapshot);" \
	       "the whole run in ParaView: output/default/fields.xdmf"; fi

# The smallest suspension deck (docs/scenes.md, "Suspension"): 95 spheres in vacuum, 40 000 steps.
# One rank unless NP is given: without a fluid every rank repeats the same particle work.
SUSPENSION_DECK := input/suspension_sphere_none.nml
SUSPENSION_NP := $(if $(filter command line environment,$(origin NP)),$(NP),1)
run-suspension: deps tools-deps ## install, build, and run the smallest suspension deck (1 rank, or NP), with ARGS
	@$(MAKE) --no-print-directory build
	$(MPIRUN) -np $(SUSPENSION_NP) $(BUILD)/agglo $(SUSPENSION_DECK) $(ARGS)

test: deps tools-deps ## install, build, and run every test (closing line "N passed, N failed")
	@$(MAKE) --no-print-directory build $(TEST_PROGRAMS)
	@BUILD=$(BUILD) tests/run_tests.sh

# The Python tools (tools/agglo-stats, tests/python) run in a venv made with Debian's python3
# (python3 on PATH may be another interpreter); the stamp makes a second call silent.
PYTHON3 := $(firstword $(wildcard /usr/bin/python3) python3)
tools-deps: deps $(VENV)/.requirements-installed ## install the Python tools' packages into .venv
	@:

$(VENV)/.requirements-installed: tools/requirements.txt
	@[ -x $(VENV)/bin/python ] || $(PYTHON3) -m venv $(VENV) \
	  || { echo "tools-deps: '$(PYTHON3) -m venv' failed (Debian package python3-venv)" >&2; exit 1; }
	@echo "tools-deps: installing tools/requirements.txt into $(VENV)"
	@$(VENV)/bin/python -m pip install -q -r tools/requirements.txt \
	  || { echo "tools-deps: pip could not install tools/requirements.txt into $(VENV)" >&2; exit 1; }
	@touch $@

bench: deps ## run the benchmarks (results for docs/performance.md)
	@$(MAKE) --no-print-directory build $(BENCH_PROGRAMS)
	@BUILD=$(BUILD) tools/bench.sh

validate: deps ## run the immersed-boundary validation ladder (the table in docs/validation.md)
	@$(MAKE) --no-print-directory build $(BUILD)/bench/bench_immersed_ladder $(BUILD)/bench/bench_immersed_surface \
	  $(BUILD)/bench/bench_immersed_moving $(BUILD)/bench/bench_immersed_cn $(BUILD)/bench/bench_immersed_squeeze \
	  $(BUILD)/bench/bench_free_particles $(BUILD)/bench/bench_free_squeeze $(BUILD)/bench/bench_free_cn \
	  $(BUILD)/bench/bench_push_pair
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_ladder
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_surface
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_moving
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_cn
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze 12 48 12 4 3 2 1.5 1 0.75 0.5
	for c in crossed parallel tip; do $(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze spheroids 4 $$c 4 2 1 0.75 0.5; done
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze spheroids 6.43 edge 4 2 1 0.75 0.5
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze spheroids 6.43 face 4 1.5
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze pressure=non_incremental
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze pressure=non_incremental viscous=0.0786 8 32 8 2 1.5 1 0.75 0.5 0.25 0.1
	for c in crossed parallel; do $(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze pressure=non_incremental viscous=0.0786 \
	  spheroids 4 $$c 4 1.5 1 0.75 0.5; done
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_immersed_squeeze pressure=non_incremental viscous=0.0786 spheroids 6.43 face 4 1.5 1 0.75 0.5
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_free_particles
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_free_squeeze
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_free_squeeze pressure=non_incremental 8 32 0.1 0 0.5 0.75 1
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_free_cn
	$(MPIRUN) -np 1 $(BUILD)/bench/bench_push_pair stokes
	for r in '8 24 0.1' '8 48 0.1' '12 36 0.1' '8 48 0.03'; do $(MPIRUN) -np 1 $(BUILD)/bench/bench_push_pair resolved $$r; done
	for r in 'needle 6 96 24 0.003' 'needle 6 96 24 0.01' 'needle 9 144 36 0.01' 'needle 6 96 48 0.01' \
	  'disk 6 32 48 10' 'disk 6 32 48 3' 'disk 9 48 72 10'; do $(MPIRUN) -np 1 $(BUILD)/bench/bench_push_pair resolved-tips $$r; done
	AGGLO=$(abspath $(BUILD))/agglo EXTREMES=long bash tests/mpi/test_resolved_extremes.sh
	@$(MAKE) --no-print-directory validate-decks

validate-decks: build ## run the validation decks through agglo and check them (validation/run.sh: one table row per case)
	AGGLO=$(abspath $(BUILD))/agglo VALIDATION_OUT=$(abspath $(BUILD))/validation-decks MPIRUN='$(MPIRUN)' bash validation/run.sh

clean: ## remove the build directory
	rm -rf $(BUILD)
