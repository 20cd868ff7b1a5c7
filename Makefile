# bkfront: library libbkfront, CLI bkfront, tests and benchmarks.
#
# `make run` and `make test` install missing Debian packages first (deps),
# then build.  Flags come from pkg-config and are expanded only when a recipe
# runs, after deps has installed what pkg-config needs.

DEB_PACKAGES := gcc make pkg-config libgsl-dev libnlopt-dev libfftw3-dev \
                libinih-dev libsundials-dev liblapacke-dev gnuplot-nox
# Only for `make valgrind` and `make fuzz` (libFuzzer ships with clang's
# runtime), so that `make test` needs neither.
VALGRIND_PACKAGES := valgrind
FUZZ_PACKAGES     := clang libclang-rt-dev
PKGS         := gsl nlopt fftw3 inih lapacke

CC       ?= cc
OPT      ?= -O2
BUILD    ?= build
PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS))
PKG_LIBS   = $(shell pkg-config --libs $(PKGS))
# SANITIZE carries instrumentation flags (make sanitize); CFLAGS from the
# command line add to, never replace, the project's own.
override CFLAGS += -std=c11 $(OPT) -g -Wall -Wextra -Werror -Iinclude $(PKG_CFLAGS) $(SANITIZE)
override LDFLAGS += $(SANITIZE)
# SUNDIALS (CVODE for the comoving simulation) ships no pkg-config file.
SUNDIALS_LIBS := -lsundials_cvode -lsundials_sunlinsolband -lsundials_sunmatrixband \
                 -lsundials_nvecserial
LDLIBS   += $(PKG_LIBS) $(SUNDIALS_LIBS) -lm

# The library's layers, lowest first (CONTRIBUTING.md): a file may include
# the headers of its own layer and of the layers before it, never after
# (tests/core/test_layers.c enforces it).  cli sits on top, outside the library.
LAYERS    := core wave stability simulation products scene
LIB_SRC   := $(foreach l,$(LAYERS),$(wildcard src/$(l)/*.c))
CLI_SRC   := $(wildcard src/cli/*.c)
# tests/*.c are the runner (main.c) and the helpers every folder shares
# (cli_support.c); the tests themselves sit in tests/LAYER/.
TEST_SRC  := $(wildcard tests/*.c tests/*/*.c)
TEST_SRC  := $(filter-out tests/fuzz/% tests/bench/%,$(TEST_SRC))
BENCH_SRC := $(wildcard tests/bench/*.c)

LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/%.o)
CLI_OBJ   := $(CLI_SRC:%.c=$(BUILD)/%.o)
TEST_OBJ  := $(TEST_SRC:%.c=$(BUILD)/%.o)
BENCH_OBJ := $(BENCH_SRC:%.c=$(BUILD)/%.o)

LIB   := $(BUILD)/libbkfront.a
CLI   := $(BUILD)/bkfront
TESTS := $(BUILD)/run_tests
BENCH := $(BUILD)/run_bench
# C programs of docs/examples/, each linked with the library alone (no CLI
# code): the proof that a product is reachable from C.
EXAMPLES := $(BUILD)/examples/check_paper

.PHONY: all test run bench sanitize deps clean build-all check-built bench-built fuzz-syntax \
        sanitize-built valgrind fuzz fuzz-built

all: deps
	@$(MAKE) --no-print-directory build-all

build-all: $(LIB) $(CLI)

# The missing ones among the Debian packages $(1): apt-get update first, then
# install (root, or sudo if not root).
define install_missing
missing=""; \
for p in $(1); do \
  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'ok installed' || missing="$$missing $$p"; \
done; \
if [ -n "$$missing" ]; then \
  echo "deps: installing$$missing"; \
  SUDO=""; [ "$$(id -u)" -ne 0 ] && SUDO=sudo; \
  $$SUDO apt-get update -qq && \
  DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing >/dev/null || exit 1; \
fi
endef

deps:
	@$(call install_missing,$(DEB_PACKAGES))

test: deps
	@$(MAKE) --no-print-directory check-built

# BKF_TEST_JOBS tests at once (default: the online CPUs), BKF_TEST_TIME_LIMIT
# seconds each (default 240).
# The benchmarks and the fuzz targets are built (the fuzz targets only
# compiled: linking them needs clang's libFuzzer, `make fuzz`) so that a
# change that breaks them fails here, not months later.
check-built: $(CLI) $(TESTS) $(BENCH) fuzz-syntax
	./$(TESTS)

fuzz-syntax:
	@for t in $(FUZZ_NAMES); do \
	  $(CC) $(CFLAGS) -Itests/fuzz -Isrc/cli -fsyntax-only tests/fuzz/fuzz_$$t.c || exit 1; \
	done

run: deps
	@$(MAKE) --no-print-directory build-all
	./$(CLI) run fronts/paper.scene

bench: deps
	@$(MAKE) --no-print-directory bench-built

bench-built: $(BENCH) $(CLI)
	./$(BENCH)
	@mkdir -p plots/out
	./$(CLI) bench --out plots/out/work_precision.tsv
	for g in plots/work_precision_*.gp; do gnuplot $$g || exit 1; done

# The whole suite under AddressSanitizer and UndefinedBehaviorSanitizer, in a
# build folder of its own.
sanitize: deps
	@$(MAKE) --no-print-directory BUILD=build/sanitize OPT="-O1" \
	  SANITIZE="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all" \
	  check-built

valgrind: deps
	@$(call install_missing,$(VALGRIND_PACKAGES))
	@$(MAKE) --no-print-directory BUILD=build/valgrind OPT="-O1" build/valgrind/bkfront build/valgrind/run_tests
	BKF_TEST_TIME_LIMIT=7200 valgrind --error-exitcode=1 --leak-check=full --trace-children=yes --trace-children-skip='*gnuplot*' -q ./build/valgrind/run_tests

# libFuzzer targets (tests/fuzz/) for the parsers of user text, built with
# clang, ASan and UBSan in a build folder of their own; each runs for
# FUZZ_SECONDS on its seed corpus tests/fuzz/corpus/NAME (new inputs go to
# build/fuzz/corpus/NAME); a crash, sanitizer report or failed check stops
# make with the input saved in build/fuzz/artifacts/.
FUZZ_SECONDS ?= 60
FUZZ_NAMES := args init lists scene

fuzz: deps
	@$(call install_missing,$(FUZZ_PACKAGES))
	@$(MAKE) --no-print-directory BUILD=build/fuzz CC=clang OPT="-O1" \
	  SANITIZE="-fsanitize=address,undefined -fsanitize=fuzzer-no-link -fno-omit-frame-pointer -fno-sanitize-recover=all" \
	  fuzz-built

fuzz-built: $(FUZZ_NAMES:%=$(BUILD)/fuzz_%)
	@for t in $(FUZZ_NAMES); do \
	  mkdir -p $(BUILD)/corpus/$$t $(BUILD)/artifacts; \
	  log=$(BUILD)/fuzz_$$t.log; \
	  ./$(BUILD)/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 \
	    -artifact_prefix=$(BUILD)/artifacts/$$t- $(BUILD)/corpus/$$t tests/fuzz/corpus/$$t \
	    >$$log 2>&1 || { tail -n 30 $$log; echo "fuzz_$$t: FINDING (input saved in $(BUILD)/artifacts/)"; exit 1; }; \
	  echo "fuzz_$$t: $$(sed -n 's/^stat::number_of_executed_units: *//p' $$log) executions in $(FUZZ_SECONDS) s, $$(ls $(BUILD)/corpus/$$t | wc -l) corpus inputs, no findings"; \
	done

.SECONDARY: $(FUZZ_NAMES:%=$(BUILD)/tests/fuzz/fuzz_%.o) \
            $(EXAMPLES:$(BUILD)/examples/%=$(BUILD)/docs/examples/%.o)
$(BUILD)/fuzz_%: $(BUILD)/tests/fuzz/fuzz_%.o $(BUILD)/src/cli/args.o $(BUILD)/src/cli/output.o $(LIB)
	$(CC) $(LDFLAGS) -fsanitize=fuzzer -o $@ $^ $(LDLIBS)

$(LIB): $(LIB_OBJ)
	$(AR) rcs $@ $^

$(CLI): $(CLI_OBJ) $(LIB)
	$(CC) $(LDFLAGS) -o $@ $(CLI_OBJ) $(LIB) $(LDLIBS)

# The tests link the CLI's parsing code too (everything but its main).
CLI_TESTABLE := $(filter-out $(BUILD)/src/cli/main.o,$(CLI_OBJ))

$(TESTS): $(TEST_OBJ) $(CLI_TESTABLE) $(LIB) $(CLI) $(EXAMPLES)
	$(CC) $(LDFLAGS) -o $@ $(TEST_OBJ) $(CLI_TESTABLE) $(LIB) $(LDLIBS)

$(BUILD)/examples/%: $(BUILD)/docs/examples/%.o $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(LIB) $(LDLIBS)

$(BENCH): $(BENCH_OBJ) $(LIB)
	$(CC) $(LDFLAGS) -o $@ $(BENCH_OBJ) $(LIB) $(LDLIBS)

# The monodromy's complex products need no C99 Annex G infinity recovery
# (its matrices are rescaled and finite); without it they run ~2x faster.
$(BUILD)/src/stability/trainspec.o: override CFLAGS += -fcx-limited-range
$(BUILD)/tests/%.o: override CFLAGS += -Itests -Isrc/cli -DBKF_CLI_PATH='"$(abspath $(CLI))"' \
  -DBKF_EXAMPLES_DIR='"$(abspath $(BUILD)/examples)"' -DBKF_SOURCE_DIR='"$(CURDIR)"'

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -MMD -MP -c -o $@ $<

clean:
	rm -rf build plots/out

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
