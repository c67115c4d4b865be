# portray: one Makefile, no configure step.
#   make              build bin/portray-master and bin/portray-worker
#   make test         build and run every test (ends with "N passed, N failed, N skipped")
#   make test-deploy  only the deployment tests (tests/deploy/*.sh: a real single-node Slurm)
#   make test-cross   clang, -ffast-math, -ffp-contract=fast and aarch64 (qemu) workers against this build
#   make bench        print speed and memory figures
#   make fuzz         run the libFuzzer targets (clang)  FUZZ_SECONDS=600
#   make install      PREFIX=/usr/local DESTDIR=  (binaries, man pages, systemd units, docs)
#   make uninstall    the same variables: removes exactly what install put there
#   make SAN=address,undefined test   sanitizer build (objects under build/san)
CC      ?= cc
OPT     ?= -O3
CSTD    := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE -ffp-contract=off -fno-math-errno
# -fno-math-errno: sqrt without an errno branch; no value changes (docs/maths.md)
WARN    := -Wall -Wextra -Wshadow -Wmissing-prototypes -Wstrict-prototypes
CFLAGS  ?= $(OPT) -g
ALL_CFLAGS = $(CSTD) $(WARN) $(CFLAGS) -I. -MMD -MP -pthread
LDLIBS  := -lm -pthread
PREFIX  ?= /usr/local
BINDIR  ?= $(PREFIX)/bin
MANDIR  ?= $(PREFIX)/share/man
DOCDIR  ?= $(PREFIX)/share/doc/portray
SYSTEMDDIR ?= $(PREFIX)/lib/systemd/system
VERSION := 0.11.0

# Link-time optimisation, gcc only: objects carry gcc's IR beside their code
# (-ffat-lto-objects); the two programs and the benchmarks are optimised whole
# when linked (3-7% fewer instructions on the SPD scenes, the same bits:
# docs/performance.md), while tests and tools link the plain code, so `make
# test` builds no slower. LTO=0 turns it off; clang and sanitizer builds
# never use it.
LTO ?= $(shell $(CC) -v 2>&1 | grep -q '^gcc version' && echo 1 || echo 0)
ifdef SAN
LTO := 0
endif
ifeq ($(LTO),1)
ALL_CFLAGS += -flto=auto -ffat-lto-objects
# the compile flags again: the code is generated at link time
LTO_LINK := $(CSTD) $(CFLAGS) -flto=auto
# everything else links the objects' plain code (gcc would otherwise run LTO
# for each of them: seconds per test)
PLAIN_LINK := -fno-lto
endif

ifdef SAN
BUILD   := build/san
ALL_CFLAGS += -fsanitize=$(SAN) -fno-sanitize-recover=all -fno-omit-frame-pointer
LDFLAGS += -fsanitize=$(SAN)
else
BUILD   := build
endif

COMMON_SRC := $(wildcard common/*.c)
PROTO_SRC  := $(wildcard proto/*.c)
MASTER_SRC := $(wildcard master/*.c)
WORKER_SRC := $(wildcard worker/*.c)
UNIT_SRC   := $(wildcard tests/unit/test_*.c)
FUZZ_SRC   := $(wildcard tests/fuzz/fuzz_*.c)
BENCH_SRC  := $(wildcard bench/bench_*.c)
TOOLS_SRC  := $(wildcard tests/tools/*.c)

obj = $(patsubst %.c,$(BUILD)/%.o,$(1))

LIBCORE  := $(BUILD)/libportray.a
CORE_OBJ := $(call obj,$(COMMON_SRC) $(PROTO_SRC))

# the master's and the worker's rooms but main, as libraries: unit tests link them
LIBMASTER := $(BUILD)/libmaster.a
LIBWORKER := $(BUILD)/libworker.a
MASTER_LIB_OBJ := $(call obj,$(filter-out master/main.c,$(MASTER_SRC)))
WORKER_LIB_OBJ := $(call obj,$(filter-out worker/main.c,$(WORKER_SRC)))

MASTER_BIN := bin/portray-master
WORKER_BIN := bin/portray-worker
UNIT_BIN   := $(patsubst tests/unit/%.c,$(BUILD)/tests/%,$(UNIT_SRC))
FUZZ_REPLAY:= $(patsubst tests/fuzz/%.c,$(BUILD)/tests/%-replay,$(FUZZ_SRC))
BENCH_BIN  := $(patsubst bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))
TOOLS_BIN  := $(patsubst tests/tools/%.c,$(BUILD)/tools/%,$(TOOLS_SRC))

.PHONY: all test test-deploy test-cross bench fuzz install uninstall clean
# keep the objects of tests, fuzz replays, benchmarks and tools, which
# chained pattern rules would delete as intermediates (named one by one: a
# bare .SECONDARY: would make every target one, and a missing one, such as
# bin/'s stamp below, would then never be remade)
.SECONDARY: $(call obj,$(UNIT_SRC) $(FUZZ_SRC) tests/fuzz/replay_main.c $(BENCH_SRC) $(TOOLS_SRC))
all: $(MASTER_BIN) $(WORKER_BIN)

$(BUILD)/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -DPORTRAY_VERSION='"$(VERSION)"' -c $< -o $@

$(LIBCORE): $(CORE_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^

$(LIBMASTER): $(MASTER_LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^

$(LIBWORKER): $(WORKER_LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && $(AR) rcs $@ $^

# bin/ holds the programs of whichever build linked them last (the tests
# run bin/): a stamp beside them names that build, so that going from the
# plain build to a sanitizer build (SAN=) or back relinks them even where
# they are newer than the other build's objects. (The cross builds of
# tests/tools/cross_build.sh put theirs, and their stamps, in their own
# directories.)
BUILT_IN := .built-in-$(subst /,-,$(BUILD))
MASTER_STAMP := $(dir $(MASTER_BIN))$(BUILT_IN)
WORKER_STAMP := $(dir $(WORKER_BIN))$(BUILT_IN)
%/$(BUILT_IN):
	@mkdir -p $(@D)
	@rm -f $(@D)/.built-in-*
	@touch $@

$(MASTER_BIN): $(BUILD)/master/main.o $(LIBMASTER) $(LIBCORE) $(MASTER_STAMP)
	$(CC) $(LTO_LINK) $(LDFLAGS) -o $@ $(filter-out $(MASTER_STAMP),$^) $(LDLIBS)

$(WORKER_BIN): $(BUILD)/worker/main.o $(LIBWORKER) $(LIBCORE) $(WORKER_STAMP)
	$(CC) $(LTO_LINK) $(LDFLAGS) -o $@ $(filter-out $(WORKER_STAMP),$^) $(LDLIBS)

$(BUILD)/tests/%: $(BUILD)/tests/unit/%.o $(LIBMASTER) $(LIBWORKER) $(LIBCORE)
	@mkdir -p $(dir $@)
	$(CC) $(PLAIN_LINK) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# Fuzz targets: replay build links tests/fuzz/replay_main.c (no libFuzzer needed).
$(BUILD)/tests/%-replay: $(BUILD)/tests/fuzz/%.o $(BUILD)/tests/fuzz/replay_main.o $(LIBCORE)
	@mkdir -p $(dir $@)
	$(CC) $(PLAIN_LINK) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/bench/%: $(BUILD)/bench/%.o $(LIBCORE)
	@mkdir -p $(dir $@)
	$(CC) $(LTO_LINK) $(LDFLAGS) -o $@ $^ $(LDLIBS)

# test tools (tests/tools/*.c): delayproxy, fakepeer
$(BUILD)/tools/%: $(BUILD)/tests/tools/%.o $(LIBCORE)
	@mkdir -p $(dir $@)
	$(CC) $(PLAIN_LINK) $(LDFLAGS) -o $@ $^ $(LDLIBS)

test: all $(UNIT_BIN) $(FUZZ_REPLAY) $(TOOLS_BIN)
	@BUILD=$(BUILD) sh tests/run.sh

# tests/deploy/*.sh through the same runner (they are part of make test too)
test-deploy: all
	@BUILD=$(BUILD) TEST_FILTER=deploy/ sh tests/run.sh

# other builds' workers (tests/tools/cross_build.sh) against this master:
# tests/e2e/cross_*.sh, which make test skips until these are built
test-cross: all $(TOOLS_BIN)
	@MAKE="$(MAKE)" sh tests/tools/cross_build.sh build/cross
	@BUILD=$(BUILD) TEST_FILTER=e2e/cross_ sh tests/run.sh

bench: all $(BENCH_BIN) $(TOOLS_BIN)
	@BUILD=$(BUILD) sh bench/run.sh

# libFuzzer builds live under build/fuzz with clang; each target runs FUZZ_SECONDS.
FUZZ_SECONDS ?= 600
FUZZ_CC ?= clang
# Undefined behaviour stops the fuzzer like a crash (UBSan would otherwise
# print and go on). Each run's whole output is kept in build/fuzz/NAME.log
# and what it found in build/fuzz/NAME-crash-* (leak-, timeout-, oom-); a
# run that ends in a crash, leak, timeout or sanitizer report fails make.
FUZZ_FLAGS := $(CSTD) -g -O1 -I. -pthread -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
fuzz:
	@mkdir -p build/fuzz
	@for f in $(FUZZ_SRC); do \
	  n=$$(basename $$f .c); \
	  echo "== $$n"; \
	  $(FUZZ_CC) $(FUZZ_FLAGS) -DPORTRAY_VERSION='"$(VERSION)"' -o build/fuzz/$$n $$f $(COMMON_SRC) $(PROTO_SRC) -lm || exit 1; \
	  mkdir -p build/fuzz/corpus-$$n; \
	  build/fuzz/$$n -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 \
	    -artifact_prefix=build/fuzz/$$n- build/fuzz/corpus-$$n tests/fuzz/corpus/$$n >build/fuzz/$$n.log 2>&1; rc=$$?; \
	  tail -n 5 build/fuzz/$$n.log; \
	  if [ $$rc -ne 0 ]; then echo "$$n: the fuzzer stopped with status $$rc (build/fuzz/$$n.log)"; exit 1; fi; \
	done

# What install puts where (uninstall removes the same list). The units name
# the binaries by their installed path: @BINDIR@ becomes $(BINDIR).
MAN1       := docs/man/portray-master.1 docs/man/portray-worker.1
MAN5       := docs/man/portray.5
UNITS      := deploy/systemd/portray-worker.service deploy/systemd/portray-worker@.service
DOCS       := README.md $(wildcard docs/*.md)
DOCS_K8S   := $(wildcard deploy/k8s/*.yaml deploy/k8s/Dockerfile)
DOCS_SLURM := $(wildcard deploy/slurm/*)

install: all
	install -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(MANDIR)/man5 \
	  $(DESTDIR)$(SYSTEMDDIR) $(DESTDIR)$(DOCDIR)
	install -m 755 $(MASTER_BIN) $(WORKER_BIN) $(DESTDIR)$(BINDIR)/
	install -m 644 $(MAN1) $(DESTDIR)$(MANDIR)/man1/
	install -m 644 $(MAN5) $(DESTDIR)$(MANDIR)/man5/
	for u in $(UNITS); do \
	  f="$(DESTDIR)$(SYSTEMDDIR)/$${u##*/}"; \
	  sed 's|@BINDIR@|$(BINDIR)|g' "$$u" >"$$f" && chmod 644 "$$f" || exit 1; \
	done
	install -m 644 $(DOCS) $(DESTDIR)$(DOCDIR)/
ifneq ($(DOCS_K8S),)
	install -d $(DESTDIR)$(DOCDIR)/deploy/k8s
	install -m 644 $(DOCS_K8S) $(DESTDIR)$(DOCDIR)/deploy/k8s/
endif
ifneq ($(DOCS_SLURM),)
	install -d $(DESTDIR)$(DOCDIR)/deploy/slurm
	install -m 644 $(DOCS_SLURM) $(DESTDIR)$(DOCDIR)/deploy/slurm/
endif

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/portray-master $(DESTDIR)$(BINDIR)/portray-worker
	rm -f $(addprefix $(DESTDIR)$(MANDIR)/man1/,$(notdir $(MAN1)))
	rm -f $(addprefix $(DESTDIR)$(MANDIR)/man5/,$(notdir $(MAN5)))
	rm -f $(addprefix $(DESTDIR)$(SYSTEMDDIR)/,$(notdir $(UNITS)))
	rm -f $(addprefix $(DESTDIR)$(DOCDIR)/,$(notdir $(DOCS)))
	rm -f $(addprefix $(DESTDIR)$(DOCDIR)/deploy/k8s/,$(notdir $(DOCS_K8S)))
	rm -f $(addprefix $(DESTDIR)$(DOCDIR)/deploy/slurm/,$(notdir $(DOCS_SLURM)))
	for d in $(DESTDIR)$(DOCDIR)/deploy/k8s $(DESTDIR)$(DOCDIR)/deploy/slurm \
	  $(DESTDIR)$(DOCDIR)/deploy $(DESTDIR)$(DOCDIR); do \
	  if [ -d "$$d" ]; then rmdir "$$d" || true; fi; \
	done

clean:
	rm -rf build bin

-include $(shell find build -name '*.d' 2>/dev/null)
