# bkfront: library libbkfront, CLI bkfront, tests and benchmarks.
#
# `make run` and `make test` install missing Debian packages first (deps),
# then build.  Flags come from pkg-config and are expanded only when a recipe
# runs, after deps has installed what pkg-config needs.

DEB_PACKAGES := gcc make pkg-config libgsl-dev libnlopt-dev libfftw3-dev \
                libinih-dev libsundials-dev liblapacke-dev libarpack2-dev gnuplot-nox \
                python3-cffi python3-numpy python3-pytest libhdf5-dev python3-h5py \
                python3-matplotlib groff-base
# Only for `make valgrind` and `make fuzz` (libFuzzer ships with clang's
# runtime), so that `make test` needs neither.
VALGRIND_PACKAGES := valgrind
# Only for `make mpi` (bkfront sweep under mpirun) and `make test-mpi`.
MPI_PACKAGES      := libopenmpi-dev openmpi-bin
FUZZ_PACKAGES     := clang libclang-rt-dev
# Only for `make bench`: the references it is timed against (AUTO-07p's
# collocation, whose equation files gfortran compiles; scipy's Radau), so
# that `make test` needs none of them.
BENCH_PACKAGES    := auto-07p gfortran python3-scipy
PKGS         := gsl nlopt fftw3 inih
# LAPACKE and ARPACK are compiled against but not linked: src/core/lazylib.c
# loads them at the first eigenvalue call (with liblapack, libblas and
# libgfortran they were over half of every process's start).
LAZY_PKGS    := lapacke
# HDF5 is compiled against but not linked: src/core/h5.c loads it at the
# first HDF5 write (its dependency tree was most of every process's start).
H5_PKG       := hdf5-serial

CC       ?= cc
OPT      ?= -O2
BUILD    ?= build
PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS) $(LAZY_PKGS) $(H5_PKG))
PKG_LIBS   = $(shell pkg-config --libs $(PKGS))
# SANITIZE carries instrumentation flags (make sanitize); CFLAGS from the
# command line add to, never replace, the project's own.
# OpenMP: bkf_sweep_run runs a sweep's points in threads (libgomp, part of gcc).
override CFLAGS += -std=c11 $(OPT) -g -Wall -Wextra -Werror -Iinclude $(PKG_CFLAGS) $(SANITIZE) -fopenmp
override LDFLAGS += $(SANITIZE) -fopenmp
# SUNDIALS (CVODE for the comoving simulation, KINSOL with SPGMR for the
# periodic orbits) ships no pkg-config file.
SUNDIALS_LIBS := -lsundials_cvodes -lsundials_kinsol -lsundials_sunlinsolband \
                 -lsundials_sunlinsolspgmr -lsundials_sunmatrixband \
                 -lsundials_nvecserial
# HDF5's dimension scales (H5DS) are in its high-level library, which
# hdf5-serial.pc does not list; its -L is that of hdf5-serial.  Only the
# tests link them (to read back what the CLI wrote).
HDF5_LIBS = -lhdf5_hl $(shell pkg-config --libs $(H5_PKG))
# The sonames h5.c and lazylib.c load: those of the libraries beside the
# headers they are compiled with (readelf reads them off the development symlinks).
lib_soname = $(shell for d in $(patsubst -L%,%,$(filter -L%,$(shell pkg-config --libs-only-L $(H5_PKG)))) \
  $(dir $(shell $(CC) -print-file-name=lib$(1).so)); do \
  [ -e $$d/lib$(1).so ] && { readelf -d $$d/lib$(1).so | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p'; break; }; done)
$(BUILD)/src/core/h5.o: override CFLAGS += -DBKF_HDF5_SONAME='"$(call lib_soname,hdf5)"' \
  -DBKF_HDF5_HL_SONAME='"$(call lib_soname,hdf5_hl)"'
# ARPACK (arpack-ng: Arnoldi for the periodic orbits' multipliers) ships a
# pkg-config file only in some versions; its library name is stable.  Both
# sonames are read off lib*.so, which liblapacke-dev and libarpack2-dev ship.
$(BUILD)/src/core/lazylib.o: override CFLAGS += -DBKF_LAPACKE_SONAME='"$(call lib_soname,lapacke)"' \
  -DBKF_ARPACK_SONAME='"$(call lib_soname,arpack)"'
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
TEST_SRC  := $(filter-out tests/fuzz/% tests/bench/% tests/audit/audit_main.c,$(TEST_SRC))
BENCH_SRC := $(wildcard tests/bench/*.c)

LIB_OBJ   := $(LIB_SRC:%.c=$(BUILD)/%.o)
CLI_OBJ   := $(CLI_SRC:%.c=$(BUILD)/%.o)
TEST_OBJ  := $(TEST_SRC:%.c=$(BUILD)/%.o)
BENCH_OBJ := $(BENCH_SRC:%.c=$(BUILD)/%.o)

LIB   := $(BUILD)/libbkfront.a
# The shared library: libbkfront.so.MAJOR.MINOR.PATCH with the SONAME
# libbkfront.so.MAJOR, exporting only the bkf_ names (src/libbkfront.map).
version_part = $(shell sed -n 's/^\#define BKF_VERSION_$(1) \([0-9]*\).*/\1/p' include/bkfront/version.h)
MAJOR   := $(call version_part,MAJOR)
VERSION := $(MAJOR).$(call version_part,MINOR).$(call version_part,PATCH)
SONAME  := libbkfront.so.$(MAJOR)
SHLIB   := $(BUILD)/libbkfront.so.$(VERSION)
CLI   := $(BUILD)/bkfront
MAN   := $(BUILD)/man
TESTS := $(BUILD)/run_tests
BENCH := $(BUILD)/run_bench
# The audit (tests/audit/): random parameter sets, every product against an
# independent route; its checks are also linked into run_tests.
AUDIT := $(BUILD)/audit
# C programs of docs/examples/, each linked with the library alone (no CLI
# code): the proof that a product is reachable from C.
EXAMPLES := $(BUILD)/examples/check_paper

.PHONY: mpi test-mpi
.PHONY: audit
.PHONY: all test run gallery bench sanitize deps clean build-all check-built bench-built fuzz-syntax \
        sanitize-built valgrind fuzz fuzz-built install uninstall FORCE

all: deps
	@$(MAKE) --no-print-directory build-all

build-all: $(LIB) $(SHLIB) $(CLI) $(MAN)/.stamp

# The manual pages: bkfront.1 and bkfront-NAME.1 for each subcommand, made
# from the CLI's own --help by src/cli/man.awk, so that they cannot drift:
# $(call man_pages,CLI,DIR).  make install installs those of the installed
# CLI (whose run --help names the installed scripts).
define man_pages
@rm -rf $(2) && mkdir -p $(2)
$(1) --help > $(2)/help.txt
awk -v page=bkfront -v version=$(VERSION) -f src/cli/man.awk \
  -v summary="$$(sed -n 's/^Description: //p' src/bkfront.pc.in)" $(2)/help.txt > $(2)/bkfront.1
awk '/^subcommands:/ { f = 1; next } f && !NF { exit } f' $(2)/help.txt | \
  while read -r name summary; do \
    $(1) help $$name > $(2)/help.txt && \
    awk -v page=bkfront-$$name -v version=$(VERSION) -v summary="$$summary" \
      -f src/cli/man.awk $(2)/help.txt > $(2)/bkfront-$$name.1 || exit 1; \
  done
@rm -f $(2)/help.txt && touch $(2)/.stamp
endef
$(MAN)/.stamp: $(CLI) src/cli/man.awk src/bkfront.pc.in
	$(call man_pages,./$(CLI),$(MAN))

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
# seconds each (default 240); each run's times, kept in $(BUILD)/test_times.tsv,
# start the next run's slowest tests first.
# The benchmarks and the fuzz targets are built (the fuzz targets only
# compiled: linking them needs clang's libFuzzer, `make fuzz`) so that a
# change that breaks them fails here, not months later.
# Beside the C suite (tests/run_suites starts both), and only outside the
# sanitizers (Python cannot load an instrumented library): tests/python/
# with pytest, the Python package over
# the shared library, compared with the CLI, and a staged `make install` that
# an external program links through pkg-config.  tests/run_suites ends with
# one line `N passed, N failed` summing both.
# Under the sanitizers only what the suite runs is built: the benchmarks,
# the audit's program and the fuzz targets' syntax are make test's (built
# there from the same sources; instrumented, nothing would run them), and
# the start order comes from make test's times (build/test_times.tsv) until
# the sanitized run has its own: CI's clone has neither at its first run.
PYTHON ?= /usr/bin/python3
check-built: $(CLI) $(TESTS) $(if $(SANITIZE),,$(BENCH) $(AUDIT) fuzz-syntax $(SHLIB))
	@BKFRONT_LIBRARY=$(abspath $(BUILD)/$(SONAME)) BKFRONT_CLI=$(abspath $(CLI)) \
	  BKF_MAKE="$(MAKE)" BKF_BUILD=$(BUILD) PYTHONPATH=$(CURDIR)/python \
	  BKF_TEST_TIMES=$(abspath $(BUILD))/test_times.tsv \
	  $(if $(SANITIZE),BKF_TEST_TIMES_SEED=$(abspath build)/test_times.tsv) \
	  tests/run_suites ./$(TESTS) $(if $(SANITIZE),,$(PYTHON) tests/python)

fuzz-syntax:
	@for t in $(FUZZ_NAMES); do \
	  $(CC) $(CFLAGS) -Itests/fuzz -Isrc/cli -fsyntax-only tests/fuzz/fuzz_$$t.c || exit 1; \
	done

# make audit [AUDIT_SETS=N] [AUDIT_SEED=S] [AUDIT_JOBS=J] [AUDIT_FLAGS=...]:
# N random sets (default 200) in J workers (default 2); exit 1 on a defect.
AUDIT_SETS ?= 200
AUDIT_SEED ?= 1
AUDIT_JOBS ?= 2
audit: deps
	@$(MAKE) --no-print-directory $(AUDIT)
	./$(AUDIT) --sets $(AUDIT_SETS) --seed $(AUDIT_SEED) --jobs $(AUDIT_JOBS) $(AUDIT_FLAGS)

run: deps
	@$(MAKE) --no-print-directory build-all
	./$(CLI) run --out plots/out/paper fronts/paper.scene

# The gallery (plots/gallery/, shown by the README and docs/scenes.md): the
# figures of the paper scene and of the check scene, drawn anew and copied
# under the names the pages use (GALLERY_PAPER: the paper scene's figures).
GALLERY_PAPER := fig1b speeds fig3a fig3b fig4a fig4b period validity profiles branch \
                 threshold spectra line diagram
gallery: deps
	@$(MAKE) --no-print-directory build-all
	./$(CLI) run --out plots/out/paper fronts/paper.scene
	./$(CLI) run --out plots/out/check fronts/check.scene
	for f in $(GALLERY_PAPER); do cp plots/out/paper/$$f.png plots/gallery/$$f.png || exit 1; done
	cp plots/out/check/check_figure.png plots/gallery/check.png

bench: deps
	@$(call install_missing,$(BENCH_PACKAGES))
	@$(MAKE) --no-print-directory bench-built

bench-built: $(BENCH) $(CLI) $(SHLIB) $(TESTS)
	BKFRONT_CLI=$(abspath $(CLI)) ./$(BENCH)
	BKFRONT_LIBRARY=$(abspath $(BUILD)/$(SONAME)) PYTHONPATH=$(CURDIR)/python \
	  $(PYTHON) tests/bench/bench_auto.py
	@mkdir -p plots/out
	./$(CLI) bench --out plots/out/work_precision.tsv
	tests/bench/bench_sweep.sh ./$(CLI)
	for g in plots/work_precision_*.gp; do gnuplot $$g || exit 1; done
	# last, on the quietest machine make bench gives: the table of timings
	# the manual quotes (docs/timings.md), the suite timed as make test runs it
	BKF_TIMINGS_SUITE="$(MAKE) --no-print-directory check-built" \
	  tests/bench/timings.sh ./$(CLI) ./$(TESTS) docs/timings.md

# The MPI build: build/mpi/bkfront, compiled with mpicc, whose `sweep` runs
# a manager/worker farm under mpirun (src/cli/sweep_mpi.c); test-mpi
# compares mpirun -np 2 and -np 3 with the serial table, on this machine
# only (shared memory and loopback).
mpi: deps
	@$(call install_missing,$(MPI_PACKAGES))
	@$(MAKE) --no-print-directory BUILD=build/mpi CC=mpicc MPI_CFLAGS=-DBKF_MPI build/mpi/bkfront

test-mpi: mpi
	@$(MAKE) --no-print-directory build-all $(TESTS)
	./$(TESTS) sweep_mpi

$(BUILD)/src/cli/sweep_mpi.o: override CFLAGS += $(MPI_CFLAGS)

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

# Position-independent, so that the same objects make the archive and the
# shared library; calls inside the library stay direct (no interposition).
# (The marker rebuilds objects compiled before this rule existed.)
$(LIB_OBJ): override CFLAGS += -fPIC -fno-semantic-interposition
# The library's own sources call LAPACKE and ARPACK under bkf_ symbols
# (include/bkfront/lazylib.h): no clash beside the real static libraries.
$(LIB_OBJ): override CFLAGS += -DBKF_LIBRARY_SOURCE
$(LIB_OBJ): $(BUILD)/.pic
$(BUILD)/.pic:
	@mkdir -p $(BUILD) && touch $@

$(SHLIB): $(LIB_OBJ) src/libbkfront.map
	$(CC) $(LDFLAGS) -shared -Wl,-soname,$(SONAME) -Wl,--version-script=src/libbkfront.map \
	  -Wl,--no-undefined -o $@ $(LIB_OBJ) $(LDLIBS)
	ln -sf $(notdir $@) $(BUILD)/$(SONAME)
	ln -sf $(SONAME) $(BUILD)/libbkfront.so

# ---------------------------------------------------------------- install
# make install [PREFIX=/usr/local] [DESTDIR=staging]: the CLI, both
# libraries, the headers, bkfront.pc (whose libdir and includedir follow
# ${prefix}, so that pkg-config --define-variable=prefix=... relocates a
# staged tree), the gnuplot scripts and example scenes (share/bkfront), the
# Python package and the manual.  uninstall removes exactly these (folders
# shared with other software stay).  The installed
# CLI is the build's, relinked with a cmd_run.o that knows PREFIX's scripts.
PREFIX     ?= /usr/local
BINDIR     ?= $(PREFIX)/bin
LIBDIR     ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
DATADIR    ?= $(PREFIX)/share/bkfront
DOCDIR     ?= $(PREFIX)/share/doc/bkfront
MANDIR     ?= $(PREFIX)/share/man
PKGCONFIGDIR ?= $(LIBDIR)/pkgconfig
# Where Debian's python3 looks for packages installed under PREFIX.
PYTHONDIR  ?= $(LIBDIR)/python$(shell $(PYTHON) -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null || echo 3)/dist-packages
INST := $(BUILD)/installed

# Rewritten only when PREFIX or a folder changes, so that what bakes them in
# is rebuilt exactly then.
$(INST)/dirs: FORCE
	@mkdir -p $(INST)
	@printf '%s\n' '$(BINDIR)' '$(LIBDIR)' '$(INCLUDEDIR)' '$(DATADIR)' '$(PYTHONDIR)' \
	  | cmp -s - $@ || printf '%s\n' '$(BINDIR)' '$(LIBDIR)' '$(INCLUDEDIR)' '$(DATADIR)' \
	  '$(PYTHONDIR)' > $@

# The build's CLI finds the scripts of this source tree; the installed one
# those of DATADIR (run --help: --plots).
$(BUILD)/src/cli/cmd_run.o: override CFLAGS += -DBKF_PLOTS_DIR='"$(CURDIR)/plots"'
$(INST)/cmd_run.o: src/cli/cmd_run.c $(INST)/dirs
	$(CC) $(CFLAGS) -DBKF_PLOTS_DIR='"$(DATADIR)/plots"' -MMD -MP -c -o $@ $<
$(INST)/bkfront: $(filter-out $(BUILD)/src/cli/cmd_run.o,$(CLI_OBJ)) $(INST)/cmd_run.o $(LIB)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# The folders the dynamic loader searches by itself (its trusted ones and
# those of ld.so.conf): a LIBDIR elsewhere ($$HOME/bkf/lib) goes into
# bkfront.pc's Libs as an rpath, so that the documented
# `cc prog.c $$(pkg-config --cflags --libs bkfront)` makes a program that runs.
LOADER_DIRS = /lib /usr/lib /lib64 /usr/lib64 $(addprefix /lib/ /usr/lib/,$(shell $(CC) -print-multiarch)) \
  $(shell ldconfig -v -N -X 2>/dev/null | sed -n 's|^\(/[^:]*\):.*|\1|p')
PC_RPATH = $(if $(filter $(LIBDIR) $(LIBDIR)/,$(LOADER_DIRS)),, -Wl,-rpath,$${libdir})
$(INST)/man/.stamp: $(INST)/bkfront src/cli/man.awk src/bkfront.pc.in
	$(call man_pages,./$(INST)/bkfront,$(INST)/man)

$(INST)/bkfront.pc: src/bkfront.pc.in $(INST)/dirs include/bkfront/version.h
	sed -e 's|@PREFIX@|$(PREFIX)|' -e 's|@LIBDIR@|$(patsubst $(PREFIX)/%,$${prefix}/%,$(LIBDIR))|' \
	  -e 's|@RPATH@|$(PC_RPATH)|' \
	  -e 's|@INCLUDEDIR@|$(patsubst $(PREFIX)/%,$${prefix}/%,$(INCLUDEDIR))|' \
	  -e 's|@VERSION@|$(VERSION)|' -e 's|@REQUIRES@|$(PKGS)|' \
	  -e 's|@LIBS_PRIVATE@|$(SUNDIALS_LIBS) -lgomp -lm|' $< > $@

# The Python package finds the shared library by its path relative to the
# package, so that a staged (DESTDIR) or moved tree still works.
$(INST)/_paths.py: $(INST)/dirs
	printf '# written by make install\nLIBRARY = %s\n' \
	  "$$($(PYTHON) -c 'import os, sys; print(repr(os.path.relpath(sys.argv[1], sys.argv[2])))' \
	     '$(LIBDIR)/$(SONAME)' '$(PYTHONDIR)/bkfront')" > $@

# The manual keeps the source tree's layout (README.md beside docs/, the
# gallery under plots/), so that its relative links resolve where installed
# (tests/python/test_install.py checks every one).
install: $(LIB) $(SHLIB) $(INST)/bkfront $(INST)/bkfront.pc $(INST)/_paths.py $(INST)/man/.stamp
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR) $(DESTDIR)$(PKGCONFIGDIR) \
	  $(DESTDIR)$(INCLUDEDIR)/bkfront $(DESTDIR)$(DATADIR)/plots $(DESTDIR)$(DATADIR)/scenes \
	  $(DESTDIR)$(PYTHONDIR)/bkfront $(DESTDIR)$(DOCDIR)/docs/cli $(DESTDIR)$(DOCDIR)/docs/examples \
	  $(DESTDIR)$(DOCDIR)/plots/gallery $(DESTDIR)$(MANDIR)/man1
	install -m 755 $(INST)/bkfront $(DESTDIR)$(BINDIR)/bkfront
	install -m 644 $(LIB) $(DESTDIR)$(LIBDIR)/libbkfront.a
	install -m 755 $(SHLIB) $(DESTDIR)$(LIBDIR)/
	ln -sf $(notdir $(SHLIB)) $(DESTDIR)$(LIBDIR)/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(LIBDIR)/libbkfront.so
	install -m 644 include/bkfront/*.h $(DESTDIR)$(INCLUDEDIR)/bkfront/
	install -m 644 $(INST)/bkfront.pc $(DESTDIR)$(PKGCONFIGDIR)/bkfront.pc
	install -m 644 plots/*.gp plots/*.awk $(DESTDIR)$(DATADIR)/plots/
	install -m 644 fronts/*.scene $(DESTDIR)$(DATADIR)/scenes/
	install -m 644 python/bkfront/*.py $(INST)/_paths.py $(DESTDIR)$(PYTHONDIR)/bkfront/
	install -m 644 README.md CONTRIBUTING.md $(DESTDIR)$(DOCDIR)/
	install -m 644 docs/*.md $(DESTDIR)$(DOCDIR)/docs/
	install -m 644 docs/cli/*.md $(DESTDIR)$(DOCDIR)/docs/cli/
	install -m 644 docs/examples/*.c $(DESTDIR)$(DOCDIR)/docs/examples/
	install -m 644 plots/gallery/*.png $(DESTDIR)$(DOCDIR)/plots/gallery/
	install -m 644 $(INST)/man/*.1 $(DESTDIR)$(MANDIR)/man1/
	@if [ -z "$(DESTDIR)" ] && [ "$$(id -u)" -eq 0 ] && command -v ldconfig >/dev/null; then ldconfig; fi

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/bkfront $(DESTDIR)$(LIBDIR)/libbkfront.a \
	  $(DESTDIR)$(LIBDIR)/libbkfront.so $(DESTDIR)$(LIBDIR)/$(SONAME) \
	  $(DESTDIR)$(LIBDIR)/$(notdir $(SHLIB)) $(DESTDIR)$(PKGCONFIGDIR)/bkfront.pc \
	  $(DESTDIR)$(MANDIR)/man1/bkfront.1 $(DESTDIR)$(MANDIR)/man1/bkfront-*.1
	rm -rf $(DESTDIR)$(INCLUDEDIR)/bkfront $(DESTDIR)$(DATADIR) $(DESTDIR)$(DOCDIR) \
	  $(DESTDIR)$(PYTHONDIR)/bkfront

$(CLI): $(CLI_OBJ) $(LIB)
	$(CC) $(LDFLAGS) -o $@ $(CLI_OBJ) $(LIB) $(LDLIBS)

# The tests link the CLI's parsing code too (everything but its main).
CLI_TESTABLE := $(filter-out $(BUILD)/src/cli/main.o,$(CLI_OBJ))

$(TESTS): $(TEST_OBJ) $(CLI_TESTABLE) $(LIB) $(CLI) $(EXAMPLES)
	$(CC) $(LDFLAGS) -o $@ $(TEST_OBJ) $(CLI_TESTABLE) $(LIB) $(LDLIBS) $(HDF5_LIBS)

$(BUILD)/examples/%: $(BUILD)/docs/examples/%.o $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $< $(LIB) $(LDLIBS)

$(BENCH): $(BENCH_OBJ) $(LIB)
	$(CC) $(LDFLAGS) -o $@ $(BENCH_OBJ) $(LIB) $(LDLIBS)

$(AUDIT): $(BUILD)/tests/audit/audit_main.o $(BUILD)/tests/audit/audit.o $(LIB)
	$(CC) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# The monodromy's complex products need no C99 Annex G infinity recovery
# (its matrices are rescaled and finite); without it they run ~2x faster.
$(BUILD)/src/stability/trainspec_radau.o $(BUILD)/src/stability/trainspec.o: override CFLAGS += -fcx-limited-range
# ETDRK4's products over the modes likewise: a field that is not finite
# stops the step (nonlinear) before a product sees it; about 18% of a run.
$(BUILD)/src/simulation/pde_etd.o: override CFLAGS += -fcx-limited-range
# The Radau step's 3x3 loops unrolled: the monodromy 17% faster (same values).
$(BUILD)/src/stability/trainspec_radau.o: override CFLAGS += -funroll-loops
$(BUILD)/tests/%.o: override CFLAGS += -Itests -Isrc/cli -DBKF_CLI_PATH='"$(abspath $(CLI))"' \
  -DBKF_EXAMPLES_DIR='"$(abspath $(BUILD)/examples)"' -DBKF_SOURCE_DIR='"$(CURDIR)"' \
  -DBKF_HDF5_SONAME='"$(call lib_soname,hdf5)"' -DBKF_LAPACKE_SONAME='"$(call lib_soname,lapacke)"' \
  -DBKF_ARPACK_SONAME='"$(call lib_soname,arpack)"' -DBKF_LIBRARY_ARCHIVE='"$(abspath $(LIB))"' \
  -DBKF_TEST_LDFLAGS='"$(LDFLAGS)"' -DBKF_TEST_LDLIBS='"$(LDLIBS)"'

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -MMD -MP -c -o $@ $<

clean:
	rm -rf build plots/out

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
