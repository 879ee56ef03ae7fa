# deformd build. Everything is found by glob so that new files need no Makefile edit:
#   core/<area>/*.c      -> build/lib/libdf_<area>.a      (math only)
#   proto/*.c            -> build/lib/libdf_proto.a       (wire format only)
#   server/*.c           -> build/bin/deformd
#   client/*.c           -> build/lib/libdeformclient.a, client/deformctl/*.c -> build/bin/deformctl
#   tests/unit/<area>/test_*.c -> build/tests/unit/<area>/test_*   (cmocka, one binary per file)
#   tests/bench/bench_*.c      -> build/bench/bench_*
#   tests/fuzz/fuzz_*.c        -> build/fuzz/fuzz_*  (clang libFuzzer, `make fuzz`)
# Release flags: -O2 -march=x86-64-v2 (SSE4.2/POPCNT: every x86-64 server of the last decade) plus
# -ffp-contract=off so float results are reproducible across builds; OpenMP for kernels.

SHELL   := /bin/bash
CC      ?= gcc
BUILD   ?= build
OPT     ?= -O2 -march=x86-64-v2 -ffp-contract=off
SAN     ?=
PYTHON  := /usr/bin/python3
MESHES  ?= $(abspath $(CURDIR)/../shared/meshes)

WARN    := -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes
CPPFLAGS := -I. -I/usr/include/suitesparse -D_GNU_SOURCE
CFLAGS  := -std=c11 $(OPT) $(SAN) $(WARN) -fopenmp -g -MMD -MP
MATH_LIBS   := -lcholmod -lsuitesparseconfig -llapacke -llapack -lopenblas -lm
SERVER_LIBS := -luv -lhidapi-hidraw -lusb-1.0 -lsqlite3 -lpthread
LDFLAGS := -fopenmp $(SAN)

AREAS      := $(notdir $(patsubst %/,%,$(wildcard core/*/)))
CORE_LIBS  := $(foreach a,$(AREAS),$(BUILD)/lib/libdf_$(a).a)
PROTO_SRC  := $(wildcard proto/*.c)
PROTO_LIB  := $(if $(PROTO_SRC),$(BUILD)/lib/libdf_proto.a)
CLIENT_SRC := $(wildcard client/*.c)
CLIENT_LIB := $(if $(CLIENT_SRC),$(BUILD)/lib/libdeformclient.a)
SERVER_SRC := $(filter-out server/main.c,$(wildcard server/*.c))
SERVER_LIB := $(if $(SERVER_SRC),$(BUILD)/lib/libdf_server.a)
CTL_SRC    := $(wildcard client/deformctl/*.c)
ALL_LIBS   := $(SERVER_LIB) $(CLIENT_LIB) $(PROTO_LIB) $(CORE_LIBS)
LINK_LIBS  := -Wl,--start-group $(ALL_LIBS) -Wl,--end-group $(MATH_LIBS)

UNIT_SRC   := $(wildcard tests/unit/*/test_*.c)
UNIT_BIN   := $(patsubst tests/unit/%.c,$(BUILD)/tests/unit/%,$(UNIT_SRC))
UNIT_HELP  := $(wildcard tests/unit/*.c)
BENCH_SRC  := $(wildcard tests/bench/bench_*.c)
BENCH_BIN  := $(patsubst tests/bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))
FUZZ_SRC   := $(wildcard tests/fuzz/fuzz_*.c)
BINS       := $(if $(wildcard server/main.c),$(BUILD)/bin/deformd) $(if $(CTL_SRC),$(BUILD)/bin/deformctl)

.PHONY: all deps test unit bench asan fuzz fuzz-build run install clean
all: $(ALL_LIBS) $(BINS) $(UNIT_BIN) $(BENCH_BIN)

# Idempotent: installs every Debian package the build, the tests and the fuzzers need.
deps:
	@if [ "$$(id -u)" = 0 ]; then SUDO=; else SUDO=sudo; fi; \
	need=$$(dpkg-query -W -f='$${Status}\n' $(DEB_PKGS) 2>/dev/null | grep -c 'install ok installed'); \
	if [ "$$need" != "$(words $(DEB_PKGS))" ]; then \
	  $$SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y --no-install-recommends $(DEB_PKGS); \
	else echo "deps: all $(words $(DEB_PKGS)) Debian packages present"; fi
DEB_PKGS := build-essential pkg-config libsuitesparse-dev liblapacke-dev libopenblas-dev \
            libuv1-dev libhidapi-dev libusb-1.0-0-dev libsqlite3-dev libcmocka-dev \
            python3 python3-pytest python3-pip python3-setuptools clang libclang-rt-14-dev

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -c $< -o $@

define area_lib
$(BUILD)/lib/libdf_$(1).a: $(patsubst %.c,$(BUILD)/obj/%.o,$(wildcard core/$(1)/*.c))
	@mkdir -p $$(dir $$@)
	rm -f $$@ && ar rcs $$@ $$^
endef
$(foreach a,$(AREAS),$(eval $(call area_lib,$(a))))

$(BUILD)/lib/libdf_proto.a: $(patsubst %.c,$(BUILD)/obj/%.o,$(PROTO_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^
$(BUILD)/lib/libdeformclient.a: $(patsubst %.c,$(BUILD)/obj/%.o,$(CLIENT_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^

$(BUILD)/lib/libdf_server.a: $(patsubst %.c,$(BUILD)/obj/%.o,$(SERVER_SRC))
	@mkdir -p $(dir $@)
	rm -f $@ && ar rcs $@ $^
$(BUILD)/bin/deformd: $(BUILD)/obj/server/main.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(LINK_LIBS) $(SERVER_LIBS)
$(BUILD)/bin/deformctl: $(patsubst %.c,$(BUILD)/obj/%.o,$(CTL_SRC)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) -o $@ $(filter %.o,$^) $(LINK_LIBS) $(SERVER_LIBS)

$(BUILD)/tests/unit/%: tests/unit/%.c $(patsubst %.c,$(BUILD)/obj/%.o,$(UNIT_HELP)) $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -o $@ $< $(patsubst %.c,$(BUILD)/obj/%.o,$(UNIT_HELP)) $(LDFLAGS) $(LINK_LIBS) $(SERVER_LIBS) -lcmocka
$(BUILD)/bench/%: tests/bench/%.c $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(CPPFLAGS) $(CFLAGS) -o $@ $< $(LDFLAGS) $(LINK_LIBS) $(SERVER_LIBS)

# The README's test command: deps, build, every suite, one closing "N passed, N failed" line.
test: deps
	$(MAKE) all fuzz-build
	BUILD=$(BUILD) MESHES=$(MESHES) PYTHON=$(PYTHON) bash tests/run_tests.sh

unit: all
	BUILD=$(BUILD) MESHES=$(MESHES) PYTHON=$(PYTHON) SUITES=unit bash tests/run_tests.sh

bench: all
	@for b in $(BENCH_BIN); do echo "== $$b"; MESHES=$(MESHES) $$b || exit 1; done

asan:
	$(MAKE) BUILD=build-asan OPT="-O1 -fno-omit-frame-pointer" SAN="-fsanitize=address,undefined -fno-sanitize-recover=undefined" all
	ASAN_OPTIONS=detect_leaks=1 SAN_FLAGS="-fsanitize=address,undefined" BUILD=build-asan MESHES=$(MESHES) PYTHON=$(PYTHON) bash tests/run_tests.sh

# libFuzzer targets: tests/fuzz/fuzz_X.c -> $(BUILD)/fuzz/fuzz_X, built by clang over the proto and core
# sources (compiled once into $(BUILD)/fuzz/obj). `make fuzz` mutates for FUZZ_SECONDS each, writing new
# inputs to $(BUILD)/fuzz/corpus/X and only reading the checked-in seeds in tests/fuzz/corpus/X.
FUZZ_SECONDS ?= 60
FUZZ_CC     := clang
FUZZ_FLAGS  := -std=c11 -g -O1 $(CPPFLAGS) -fsanitize=address,undefined -fopenmp=libgomp
FUZZ_LIBSRC := $(PROTO_SRC) $(wildcard core/*/*.c)
FUZZ_OBJ    := $(patsubst %.c,$(BUILD)/fuzz/obj/%.o,$(FUZZ_LIBSRC))
FUZZ_BIN    := $(patsubst tests/fuzz/%.c,$(BUILD)/fuzz/%,$(FUZZ_SRC))

$(BUILD)/fuzz/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_FLAGS) -fsanitize=fuzzer-no-link -c $< -o $@
$(BUILD)/fuzz/%: tests/fuzz/%.c $(FUZZ_OBJ)
	@mkdir -p $(dir $@)
	$(FUZZ_CC) $(FUZZ_FLAGS) -fsanitize=fuzzer $< $(FUZZ_OBJ) -o $@ $(MATH_LIBS) -lgomp

.SECONDARY: $(FUZZ_OBJ)
fuzz-build: $(FUZZ_BIN)
fuzz: fuzz-build
	@for b in $(FUZZ_BIN); do n=$$(basename $$b); c=$${n#fuzz_}; mkdir -p $(BUILD)/fuzz/corpus/$$c; \
	  echo "== $$n for $(FUZZ_SECONDS) s"; \
	  $$b -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 $(BUILD)/fuzz/corpus/$$c tests/fuzz/corpus/$$c || exit 1; done

run: all
	bash tests/demo_run.sh

# Installs the daemon, deformctl, the systemd units, libdeformclient (static, with the libraries it
# needs), its header tree under include/deformd/ and a pkg-config file:
#   cc app.c $$(pkg-config --cflags --libs deformclient)   with  #include <deformclient.h>
PREFIX  ?= /usr/local
DESTDIR ?=
CLIENT_HEADERS := core/common/df_error.h core/mesh/mesh.h core/mesh/mesh_io.h \
                  proto/frame.h proto/buf.h proto/frame_codec.h proto/wire_error.h proto/messages.h \
                  proto/wire_schema.h
install: all
	install -d $(DESTDIR)$(PREFIX)/bin $(DESTDIR)$(PREFIX)/lib/pkgconfig \
	  $(DESTDIR)$(PREFIX)/lib/systemd/system $(DESTDIR)$(PREFIX)/share/doc/deformd
	install -m 755 $(BUILD)/bin/deformd $(BUILD)/bin/deformctl $(DESTDIR)$(PREFIX)/bin/
	install -m 644 $(CLIENT_LIB) $(PROTO_LIB) $(CORE_LIBS) $(DESTDIR)$(PREFIX)/lib/
	for h in $(CLIENT_HEADERS); do install -D -m 644 $$h $(DESTDIR)$(PREFIX)/include/deformd/$$h; done
	install -m 644 client/deformclient.h $(DESTDIR)$(PREFIX)/include/deformd/deformclient.h
	sed 's|@PREFIX@|$(PREFIX)|' client/deformclient.pc.in > $(DESTDIR)$(PREFIX)/lib/pkgconfig/deformclient.pc
	sed 's|/usr/local/bin/|$(PREFIX)/bin/|' systemd/deformd.service > $(DESTDIR)$(PREFIX)/lib/systemd/system/deformd.service
	install -m 644 systemd/deformd.socket $(DESTDIR)$(PREFIX)/lib/systemd/system/
	install -m 644 systemd/deformd.conf.example proto/PROTOCOL.md $(DESTDIR)$(PREFIX)/share/doc/deformd/

clean:
	rm -rf build build-asan

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
