# deformd build. Everything is found by glob (find: subfolders included) so that new files and
# folders need no Makefile edit:
#   core/<area>/**/*.c   -> build/lib/libdf_<area>.a      (math only)
#   proto/**/*.c         -> build/lib/libdf_proto.a       (wire format only)
#   server/**/*.c        -> build/lib/libdf_server.a + server/main.c -> build/bin/deformd
#   client/**/*.c        -> build/lib/libdeformclient.a   (minus client/deformctl/, client/python/)
#   client/deformctl/**/*.c -> build/bin/deformctl
#   tests/unit/<area>/**/test_*.c -> build/tests/unit/<area>/.../test_*  (cmocka, one per file)
#   tests/bench/bench_*.c      -> build/bench/bench_*
#   tests/fuzz/fuzz_*.c        -> build/fuzz/fuzz_*  (clang libFuzzer, `make fuzz`)
# Layers (tests/check_layers.sh, run by `make test`, holds the allowed #include matrix):
#   core <- proto <- client <- deformctl;  core, proto <- server. Each binary links its layers only:
#   deformd: server proto core + libuv + Embree (core/geom); deformctl: client proto mesh common kelvinlet (local brush
#   check); libdeformclient needs proto mesh common only (client/deformclient.pc.in).
# Release flags: -O2 -march=x86-64-v2 (SSE4.2/POPCNT: every x86-64 server of the last decade) plus
# -ffp-contract=off so float results are reproducible across builds; OpenMP for kernels (OMP).
# Sanitizer builds: `make asan` (build-asan), `make tsan` (build-tsan: kernels serial, no
# target_clones; see the tsan target).

SHELL   := /bin/bash
CC      ?= gcc
BUILD   ?= build
OPT     ?= -O2 -march=x86-64-v2 -ffp-contract=off
SAN     ?=
OMP     ?= -fopenmp
DEFS    ?=
PYTHON  := /usr/bin/python3
MESHES  ?= $(abspath $(CURDIR)/../shared/meshes)

WARN    := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes
CPPFLAGS := -I. -I/usr/include/suitesparse -D_GNU_SOURCE $(DEFS)
CFLAGS  := -std=c11 $(OPT) $(SAN) $(WARN) $(OMP) -g -MMD -MP
LDFLAGS := $(OMP) $(SAN)
# System libraries per layer (SQLite and zstd (libzstd-dev, the packed change deltas of
# server/store/codec.c): server/store/, in SERVER_SYS). HID_SYS: the
# device sources of server/hid/ (hid_hidapi.c: hidapi-hidraw, hid_libusb.c: libusb-1.0; headers
# included as <hidapi/hidapi.h>, <libusb-1.0/libusb.h>, so no -I is needed).
KELV_SYS    := -llapacke -llapack -lopenblas -lm
MATH_LIBS   := -lcholmod -lsuitesparseconfig -llapacke -llapack -lopenblas -lm
HID_SYS     := -lhidapi-hidraw -lusb-1.0
# CRYPTO_SYS: OpenSSL libssl + libcrypto, for proto/auth_mac.c (HMAC-SHA256 of AUTH) and TLS
# (server/net/tls.c, client/dc_tls.c), linked by everything that links the proto layer's auth
# (the daemon, libdeformclient users, their unit tests); and libzstd (libzstd-dev), which
# libdeformclient uses for the zstd stream encoding (client/dc_stream_enc.c, PROTOCOL.md 6.3).
CRYPTO_SYS  := -lssl -lcrypto -lzstd
SERVER_SYS  := -luv $(HID_SYS) -lsqlite3 -lzstd -lhiredis -lpthread $(CRYPTO_SYS)
# core/geom (the pen's ray cast): Embree 3 (libembree-dev), linked by what uses core/geom: the
# daemon (server/hid/hid_pen_target.c), the geom and server unit tests, the benches, the fuzzers
# (they compile every core source).
GEOM_SYS    := -lembree3
# libpng (libpng-dev): deformctl's PNG output (client/deformctl/png_out.c, `deformctl preview`),
# linked by deformctl and its unit tests only; libdeformclient does not need it.
PNG_SYS     := -lpng

srcs = $(if $(wildcard $(1)),$(shell find $(1) -name '*.c' $(2) | sort))
lib  = $(BUILD)/lib/libdf_$(1).a
objs = $(patsubst %.c,$(BUILD)/obj/%.o,$(1))
AREAS      := $(notdir $(patsubst %/,%,$(wildcard core/*/)))
CORE_LIBS  := $(foreach a,$(AREAS),$(call lib,$(a)))
PROTO_SRC  := $(call srcs,proto)
PROTO_LIB  := $(if $(PROTO_SRC),$(call lib,proto))
CLIENT_SRC := $(call srcs,client,-not -path 'client/deformctl/*' -not -path 'client/python/*')
CLIENT_LIB := $(if $(CLIENT_SRC),$(BUILD)/lib/libdeformclient.a)
SERVER_SRC := $(call srcs,server,-not -path server/main.c)
SERVER_LIB := $(if $(SERVER_SRC),$(call lib,server))
CTL_SRC    := $(call srcs,client/deformctl)
CTL_LIB    := $(if $(CTL_SRC),$(BUILD)/lib/libdf_ctl.a)
ALL_LIBS   := $(SERVER_LIB) $(CTL_LIB) $(CLIENT_LIB) $(PROTO_LIB) $(CORE_LIBS)
group      = -Wl,--start-group $(1) -Wl,--end-group
# What each binary links (archives, then system libraries).
BASE_LIBS   := $(call lib,mesh) $(call lib,common)
CLIENT_LINK := $(CLIENT_LIB) $(PROTO_LIB) $(BASE_LIBS)
CTL_LINK    := $(CTL_LIB) $(CLIENT_LINK) $(call lib,kelvinlet)
SERVER_LINK := $(SERVER_LIB) $(PROTO_LIB) $(CORE_LIBS)

UNIT_SRC   := $(call srcs,tests/unit,-mindepth 2 -name 'test_*.c')
UNIT_BIN   := $(patsubst tests/unit/%.c,$(BUILD)/tests/unit/%,$(UNIT_SRC))
UNIT_AREAS := $(sort $(foreach t,$(UNIT_SRC),$(word 3,$(subst /, ,$(t)))))
UNIT_HELP  := $(wildcard tests/unit/*.c)
# C unit tests link their area's layers: a core area its library plus mesh and common, proto its
# layer, client the client layer plus core (test_parity checks it against the solvers), deformctl
# what deformctl links (its objects but main are the archive libdf_ctl.a), server what deformd
# links.
$(foreach a,$(AREAS),$(eval UNIT_LINK_$(a) := $(call lib,$(a)) $(BASE_LIBS)))
$(foreach a,$(AREAS),$(eval UNIT_SYS_$(a) := $(MATH_LIBS)))
# admm: test_admm_kguess seeds the solver with core/kelvinlet's guess
UNIT_LINK_admm      := $(call lib,admm) $(call lib,kelvinlet) $(BASE_LIBS)
UNIT_SYS_common     := -lm
UNIT_SYS_mesh       := -lm
UNIT_SYS_kelvinlet  := $(KELV_SYS)
UNIT_SYS_geom       := $(GEOM_SYS) -lm
UNIT_LINK_proto     := $(PROTO_LIB) $(BASE_LIBS)
UNIT_SYS_proto      := -lm $(CRYPTO_SYS)
UNIT_LINK_client    := $(CLIENT_LIB) $(PROTO_LIB) $(CORE_LIBS)
UNIT_SYS_client     := $(MATH_LIBS) $(CRYPTO_SYS)
UNIT_LINK_deformctl := $(CTL_LINK)
UNIT_SYS_deformctl  := $(KELV_SYS) $(CRYPTO_SYS) $(PNG_SYS)
UNIT_LINK_server    := $(SERVER_LINK)
UNIT_SYS_server     := $(MATH_LIBS) $(GEOM_SYS) $(SERVER_SYS)
# hid: server/hid/ (parsers: core/common only; device sources: hidapi, libusb, pthread), taken
# from the server archive.
UNIT_LINK_hid       := $(SERVER_LIB) $(call lib,common)
UNIT_SYS_hid        := -lm $(HID_SYS) -lsqlite3 -lzstd -lpthread
BENCH_SRC  := $(wildcard tests/bench/bench_*.c)
BENCH_BIN  := $(patsubst tests/bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))
FUZZ_SRC   := $(wildcard tests/fuzz/fuzz_*.c)
BINS       := $(if $(wildcard server/main.c),$(BUILD)/bin/deformd) $(if $(CTL_SRC),$(BUILD)/bin/deformctl)
# The Blender add-on (client/blender/deformd_blender) as an installable zip with the Python client
# package (client/python/deformd_client) vendored in as deformd_blender/deformd_client: copied
# here by the build, never kept as a copy in the tree.
ADDON_SRC  := $(shell find client/blender/deformd_blender client/python/deformd_client -name '*.py' 2>/dev/null)
ADDON_ZIP  := $(if $(wildcard client/blender/deformd_blender),$(BUILD)/blender/deformd_blender.zip)

.PHONY: all deps test unit bench asan tsan tsan-build fuzz fuzz-build run install uninstall clean
all: $(ALL_LIBS) $(BINS) $(UNIT_BIN) $(BENCH_BIN) $(ADDON_ZIP)

# Idempotent: installs every Debian package the build, the tests and the fuzzers need (hidapi,
# libusb for the HID device sources; SQLite for the durable-store work, nothing links it yet;
# systemd for `systemd-analyze verify/security` of the units and systemd-socket-activate,
# python3-seccomp and strace for running deformd under the unit's system-call filter and
# auditing the paths it opens (tests/integration/test_systemd.py), man-db (with groff-base)
# for rendering the man pages in tests/integration/test_man.py; blender (3.4.1) and
# python3-numpy, which Debian's blender does not pull in, for the add-on's tests and bench, and
# xvfb + xauth for its GUI test under xvfb-run).
deps:
	@if [ "$$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi; \
	need=$$(dpkg-query -W -f='$${Status}\n' $(DEB_PKGS) 2>/dev/null | grep -c 'install ok installed'); \
	if [ "$$need" != "$(words $(DEB_PKGS))" ]; then \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y --no-install-recommends $(DEB_PKGS); \
	else echo "deps: all $(words $(DEB_PKGS)) Debian packages present"; fi
DEB_PKGS := build-essential pkg-config libsuitesparse-dev liblapacke-dev libopenblas-dev \
            libuv1-dev libhidapi-dev libusb-1.0-0-dev libsqlite3-dev libcmocka-dev \
            python3 python3-pytest python3-pip python3-setuptools clang libclang-rt-14-dev \
             libembree-dev systemd python3-seccomp strace man-db libssl-dev libzstd-dev \
            blender python3-numpy xvfb xauth libpng-dev redis-server libhiredis-dev

# (the folders are prerequisites too: a removed module rebuilds the zip)
$(BUILD)/blender/deformd_blender.zip: $(ADDON_SRC) client/blender/deformd_blender client/python/deformd_client
	rm -rf $(BUILD)/blender/stage && mkdir -p $(BUILD)/blender/stage
	cp -r client/blender/deformd_blender $(BUILD)/blender/stage/
	cp -r client/python/deformd_client $(BUILD)/blender/stage/deformd_blender/
	find $(BUILD)/blender/stage -name __pycache__ -prune -exec rm -rf {} +
	rm -f $@ && cd $(BUILD)/blender/stage && $(PYTHON) -m zipfile -c ../$(notdir $@) deformd_blender

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

define area_lib
$(call lib,$(1)): $(call objs,$(call srcs,core/$(1)))
	@mkdir -p $$(dir $$@)
	rm -f $$@ && ar rcs $$@ $$^
endef
$(foreach a,$(AREAS),$(eval $(call area_lib,$(a))))

$(BUILD)/lib/libdf_proto.a: $(call objs,$(PROTO_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^
$(BUILD)/lib/libdeformclient.a: $(call objs,$(CLIENT_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(BUILD)/lib/libdf_server.a: $(call objs,$(SERVER_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^
$(BUILD)/bin/deformd: $(BUILD)/obj/server/main.o $(SERVER_LINK)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(call group,$(SERVER_LINK)) $(MATH_LIBS) $(GEOM_SYS) \
	  $(SERVER_SYS)
$(BUILD)/lib/libdf_ctl.a: $(call objs,$(filter-out client/deformctl/main.c,$(CTL_SRC)))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^
$(BUILD)/bin/deformctl: $(BUILD)/obj/client/deformctl/main.o $(CTL_LINK)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(call group,$(CTL_LINK)) $(KELV_SYS) $(CRYPTO_SYS) \
	  $(PNG_SYS)

define unit_area
$(BUILD)/tests/unit/$(1)/%: tests/unit/$(1)/%.c $(call objs,$(UNIT_HELP)) $$(UNIT_LINK_$(1))
	@mkdir -p $$(dir $$@)
	$$(CC) $$(CPPFLAGS) $$(CFLAGS) -o $$@ $$< $(call objs,$(UNIT_HELP)) $$(LDFLAGS) \
	  $$(call group,$$(UNIT_LINK_$(1))) $$(UNIT_SYS_$(1)) -lcmocka
endef
$(foreach a,$(UNIT_AREAS),$(eval $(call unit_area,$(a))))
$(BUILD)/bench/%: tests/bench/%.c $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -o $@ $< $(LDFLAGS) $(call group,$(ALL_LIBS)) $(MATH_LIBS) \
	  $(GEOM_SYS) $(SERVER_SYS)

# The README's test command: deps, build, every suite, one closing "N passed, N failed" line.
test: deps
	$(MAKE) all fuzz-build
	BUILD=$(BUILD) MESHES=$(MESHES) PYTHON=$(PYTHON) bash tests/run_tests.sh

unit: all
	BUILD=$(BUILD) MESHES=$(MESHES) PYTHON=$(PYTHON) SUITES=unit bash tests/run_tests.sh

# C benches (build/bench/bench_*), then the Python ones (tests/bench/bench_*.py, against the built
# daemon); each prints its figures with their targets (timing lives here, never in make test).
bench: all
	@for b in $(BENCH_BIN); do echo "== $$b"; MESHES=$(MESHES) $$b || exit 1; done
	@for p in $(wildcard tests/bench/bench_*.py); do echo "== $$p"; \
	  PYTHONPATH=client/python:tests/integration BUILD=$(BUILD) MESHES=$(MESHES) $(PYTHON) $$p \
	  || exit 1; done

# The fuzzers are ASan+UBSan builds already (make test runs them): here the unit and integration suites.
asan:
	$(MAKE) BUILD=build-asan OPT="-O1 -fno-omit-frame-pointer" SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" all
	ASAN_OPTIONS=detect_leaks=1 SAN_FLAGS="-fsanitize=address,undefined" BUILD=build-asan MESHES=$(MESHES) PYTHON=$(PYTHON) SUITES="unit integration" bash tests/run_tests.sh

# ThreadSanitizer: the daemon, deformctl, the client library and the server unit tests in
# build-tsan, then those tests and the integration suite; any report fails the run (halt_on_error,
# exitcode 66; the pytest fixtures also fail a test whose daemon log holds a TSan warning).
# Kernels are serial (OMP=-fopenmp-simd: `omp simd` kept, no libgomp, which TSan cannot see
# into: its barriers would show as races) and DF_NO_TARGET_CLONES drops the Kelvinlet kernel's
# ifunc clones (their resolver runs before the TSan runtime is up and crashes deformd at load).
# OMP_THREAD_LIMIT=1 (and OMP_NUM_THREADS / OPENBLAS_NUM_THREADS=1): the prebuilt CHOLMOD opens
# its own libgomp teams with a fixed num_threads (4) that OMP_NUM_THREADS does not cap; a TSan
# deformd then reported cholmod_clear_flag's memset in df_admm_create racing a libgomp thread.
# With the thread limit every region runs on the calling worker, where TSan sees each access.
# No suppressions.
# Left out under TSan (every other integration test runs): test_inline's cheap-update test needs
# an update to cost under the largest inline budget (1000 us), which TSan's ~10x slowdown breaks
# (a cost assumption, not a race check; under TSan few updates qualify to run inline at all).
TSAN_DESELECT := --deselect \
  tests/integration/test_inline.py::test_cheap_updates_run_inline_and_match_the_pool_path
TSAN_BUILD := build-tsan
TSAN_VARS  := BUILD=$(TSAN_BUILD) OPT="-O1 -fno-omit-frame-pointer" SAN=-fsanitize=thread \
              OMP=-fopenmp-simd DEFS=-DDF_NO_TARGET_CLONES
tsan:
	$(MAKE) $(TSAN_VARS) tsan-build
	TSAN_OPTIONS="halt_on_error=1 exitcode=66 second_deadlock_stack=1" SAN_FLAGS=-fsanitize=thread \
	  OMP_THREAD_LIMIT=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
	  BUILD=$(TSAN_BUILD) MESHES=$(MESHES) PYTHON=$(PYTHON) SUITES="unit integration" \
	  PYTEST_ARGS="$(TSAN_DESELECT)" bash tests/run_tests.sh
tsan-build: $(ALL_LIBS) $(BINS) $(filter $(BUILD)/tests/unit/server/%,$(UNIT_BIN)) $(ADDON_ZIP) \
            $(BUILD)/bench/bench_load

# libFuzzer targets: tests/fuzz/fuzz_X.c -> $(BUILD)/fuzz/fuzz_X, built by clang over the proto and core
# sources (compiled once into $(BUILD)/fuzz/obj; -MMD -MP: header changes rebuild them; their .d
# files are included at the end). `make fuzz` mutates for FUZZ_SECONDS each, writing new
# inputs to $(BUILD)/fuzz/corpus/X and only reading the checked-in seeds in tests/fuzz/corpus/X.
FUZZ_SECONDS ?= 60
FUZZ_CC     := clang
FUZZ_FLAGS  := -std=c11 -g -O1 $(CPPFLAGS) -fsanitize=address,undefined -fopenmp=libgomp -MMD -MP
# server/hid: its pure code only (the device sources and the manager need hidapi/libusb/libuv).
FUZZ_HID_IO := $(addprefix server/hid/,hid_hidapi.c hid_libusb.c hid_manager.c hid_mgr_%)
FUZZ_LIBSRC := $(PROTO_SRC) $(call srcs,core) $(filter-out $(FUZZ_HID_IO),$(call srcs,server/hid))
FUZZ_OBJ    := $(patsubst %.c,$(BUILD)/fuzz/obj/%.o,$(FUZZ_LIBSRC))
FUZZ_BIN    := $(patsubst tests/fuzz/%.c,$(BUILD)/fuzz/%,$(FUZZ_SRC))

$(BUILD)/fuzz/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_FLAGS) -fsanitize=fuzzer-no-link -c $< -o $@
# Linked through an archive: a fuzzer takes only the objects it needs, so sources whose system
# libraries the fuzzers do not link (server/hid device code, Embree) cannot break the link.
FUZZ_LIB    := $(BUILD)/fuzz/lib/libdf_fuzz.a
$(FUZZ_LIB): $(FUZZ_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^
$(BUILD)/fuzz/%: tests/fuzz/%.c $(FUZZ_LIB)
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_FLAGS) -fsanitize=fuzzer $< $(FUZZ_LIB) -o $@ $(MATH_LIBS) $(GEOM_SYS) -lgomp

.SECONDARY: $(FUZZ_OBJ)
fuzz-build: $(FUZZ_BIN)
fuzz: fuzz-build
	@for b in $(FUZZ_BIN); do n=$$(basename $$b); c=$${n#fuzz_}; mkdir -p $(BUILD)/fuzz/corpus/$$c; \
	  echo "== $$n for $(FUZZ_SECONDS) s"; \
	  $$b -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 $(BUILD)/fuzz/corpus/$$c tests/fuzz/corpus/$$c || exit 1; done

# Like test: installs the Debian packages first, so it works as the first command on a fresh machine.
run: deps
	$(MAKE) all
	BUILD=$(BUILD) MESHES=$(MESHES) bash tests/demo_run.sh

# Installs the daemon, deformctl, the systemd units (deformd.service with ExecStart= and
# Documentation= pointing into PREFIX), the sysusers.d file (user and group deformd) and the udev
# rules (HID nodes for the group deformd), the man pages deformd(8), deformd.conf(5),
# deformctl(1) under share/man, libdeformclient (static, with the libraries it
# needs: client, proto, mesh, common), only the public header deformclient.h and the project headers
# it includes (computed by the compiler: CLIENT_HEADERS) under include/deformd/, a pkg-config file,
# and the documents the units name (Documentation=: README.md, PROTOCOL.md) under share/doc/deformd:
#   cc app.c $$(pkg-config --cflags --libs deformclient)   with  #include <deformclient.h>
# `make uninstall` (same PREFIX and DESTDIR) removes every file install installs and then the
# directories it made that are left empty (never PREFIX itself).
PREFIX  ?= /usr/local
DESTDIR ?=
DOCDIR  := $(PREFIX)/share/doc/deformd
MANDIR  := $(PREFIX)/share/man
UNITDIR := $(PREFIX)/lib/systemd/system
# man pages live beside their program; installed to share/man/man<section>/ by their suffix.
MAN_PAGES := client/deformctl/deformctl.1 server/man/deformd.conf.5 server/man/deformd.8
man_dest = $(DESTDIR)$(MANDIR)/man$(subst .,,$(suffix $(1)))/$(notdir $(1))
CLIENT_INSTALL_LIBS := $(CLIENT_LIB) $(PROTO_LIB) $(BASE_LIBS)
CLIENT_HEADERS = $(filter-out client/deformclient.h,$(filter %.h,$(shell $(CC) $(CPPFLAGS) -MM \
                   client/deformclient.h)))
INSTALL_DIRS := bin lib/pkgconfig lib/systemd/system lib/sysusers.d lib/udev/rules.d \
                share/doc/deformd share/man/man1 share/man/man5 share/man/man8
install: all
	install -d $(addprefix $(DESTDIR)$(PREFIX)/,$(INSTALL_DIRS))
	install -m 755 $(BUILD)/bin/deformd $(BUILD)/bin/deformctl $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(CLIENT_INSTALL_LIBS) $(DESTDIR)$(PREFIX)/lib/
	for h in $(CLIENT_HEADERS); do install -D -m 644 $$h $(DESTDIR)$(PREFIX)/include/deformd/$$h; done
	install -m 644 client/deformclient.h $(DESTDIR)$(PREFIX)/include/deformd/deformclient.h
	sed 's|@PREFIX@|$(PREFIX)|' client/deformclient.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/deformclient.pc
	sed -e 's|/usr/local/bin/|$(PREFIX)/bin/|' \
	  -e 's|file:///usr/share/doc/deformd/|file://$(DOCDIR)/|' \
	  systemd/deformd.service > $(DESTDIR)$(UNITDIR)/deformd.service
	install -m 644 systemd/deformd.socket $(DESTDIR)$(UNITDIR)/
	install -m 644 systemd/deformd.sysusers.conf $(DESTDIR)$(PREFIX)/lib/sysusers.d/deformd.conf
	install -m 644 systemd/70-deformd.rules $(DESTDIR)$(PREFIX)/lib/udev/rules.d/
	$(foreach m,$(MAN_PAGES),install -m 644 $(m) $(call man_dest,$(m)) &&) true
	install -m 644 systemd/deformd.conf.example README.md proto/PROTOCOL.md $(DESTDIR)$(DOCDIR)/

uninstall:
	rm -f $(addprefix $(DESTDIR)$(PREFIX)/bin/,deformd deformctl) \
	  $(addprefix $(DESTDIR)$(PREFIX)/lib/,$(notdir $(CLIENT_INSTALL_LIBS))) \
	  $(DESTDIR)$(PREFIX)/lib/pkgconfig/deformclient.pc \
	  $(DESTDIR)$(UNITDIR)/deformd.service $(DESTDIR)$(UNITDIR)/deformd.socket \
	  $(DESTDIR)$(PREFIX)/lib/sysusers.d/deformd.conf \
	  $(DESTDIR)$(PREFIX)/lib/udev/rules.d/70-deformd.rules \
	  $(foreach m,$(MAN_PAGES),$(call man_dest,$(m)))
	rm -rf $(DESTDIR)$(PREFIX)/include/deformd $(DESTDIR)$(DOCDIR)
	for d in $(INSTALL_DIRS) include; do p=$(DESTDIR)$(PREFIX)/$$d; \
	  while [ "$$p" != "$(DESTDIR)$(PREFIX)" ]; do \
	    if [ -d "$$p" ]; then rmdir "$$p" 2>/dev/null || break; fi; p=$$(dirname "$$p"); done; done

clean:
	rm -rf build build-asan build-tsan

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
