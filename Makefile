# Thin front end over tools/setup.sh and CMake: `make demo` and `make test` are all a newcomer
# needs. Everything real lives in CMakeLists.txt.
BUILD_DIR     ?= build
SANITIZE_DIR  ?= build-sanitize
TSAN_DIR      ?= build-tsan
CLANG_DIR     ?= build-clang
LTO_DIR       ?= build-lto
BUILD_TYPE    ?= Release
CMAKE         ?= /usr/bin/cmake
CTEST         ?= /usr/bin/ctest
PYTHON        := $(CURDIR)/.venv/bin/python
# The same for the shell, in single quotes (each ' of it as '\''): a checkout's folder may hold
# spaces, '&', '$', parentheses or quotes, which the shell would otherwise split or act on.
PYTHON_ARG     = '$(subst ','\'',$(PYTHON))'
JOBS          ?= 2
CMAKE_FLAGS   ?=
# make fuzz: seconds per target, and the targets (model_file mesh_file simulation_state fmu_state reference inputs; all when empty).
FUZZ_SECONDS  ?= 60
FUZZ_TARGETS  ?=

.PHONY: all setup build demo test sanitize-build test-sanitize test-thread-sanitize test-clang test-lto bench-forces bench-cloth fuzz install clean

all: build

setup:
	@tools/setup.sh

# BUILD_TYPE or CMAKE_FLAGS given to make (on its command line or in the environment) configure
# an existing build folder again with them; otherwise a folder configured once keeps its settings.
# The sanitizer folders have their own build types, so only CMAKE_FLAGS configures them again.
ifneq ($(filter-out file default undefined,$(origin BUILD_TYPE) $(origin CMAKE_FLAGS)),)
CONFIGURE_AGAIN := configure-again
endif
ifneq ($(filter-out file default undefined,$(origin CMAKE_FLAGS)),)
CONFIGURE_FLAGS_AGAIN := configure-again
endif
.PHONY: configure-again
configure-again:

$(BUILD_DIR)/build.ninja: $(CONFIGURE_AGAIN) | setup
	$(CMAKE) -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) \
	    -DSPRINGMASS_PYTHON=$(PYTHON_ARG) $(CMAKE_FLAGS)

build: setup $(BUILD_DIR)/build.ninja
	$(CMAKE) --build $(BUILD_DIR) -j $(JOBS)

demo: build
	tools/demo.sh $(BUILD_DIR)

test: build
	$(CTEST) --test-dir $(BUILD_DIR) --output-on-failure -j $(JOBS)

$(SANITIZE_DIR)/build.ninja: $(CONFIGURE_FLAGS_AGAIN) | setup
	$(CMAKE) -S . -B $(SANITIZE_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Debug \
	    -DSPRINGMASS_SANITIZE=ON -DSPRINGMASS_PYTHON=$(PYTHON_ARG) $(CMAKE_FLAGS)

sanitize-build: setup $(SANITIZE_DIR)/build.ninja
	$(CMAKE) --build $(SANITIZE_DIR) -j $(JOBS)

test-sanitize: sanitize-build
	$(CTEST) --test-dir $(SANITIZE_DIR) --output-on-failure -j $(JOBS)

# ThreadSanitizer: only the executables of the tests that use threads are built and run.
$(TSAN_DIR)/build.ninja: $(CONFIGURE_FLAGS_AGAIN) | setup
	$(CMAKE) -S . -B $(TSAN_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	    -DSPRINGMASS_SANITIZE_THREAD=ON -DSPRINGMASS_PYTHON=$(PYTHON_ARG) $(CMAKE_FLAGS)

test-thread-sanitize: setup $(TSAN_DIR)/build.ninja
	$(CMAKE) --build $(TSAN_DIR) -j $(JOBS) --target test_threads test_simulation test_fmu
	$(CTEST) --test-dir $(TSAN_DIR) --output-on-failure -j $(JOBS) -L threads

# Clang, for the processor it runs on: the tests that the SIMD loops (forces, Jacobians, vector
# operations) give the scalar code's bits, under a compiler that contracts a * b + c into a fused
# multiply-add unless told not to (CMakeLists.txt). Installs clang if missing, and clang's OpenMP
# (libomp-14-dev), which SUNDIALS' CMake package asks for.
test-clang: setup
	@need=; command -v clang > /dev/null || need=clang; \
	    dpkg-query -W -f='$${Status}' libomp-14-dev 2>/dev/null | grep -q "install ok installed" || \
	    need="$$need libomp-14-dev"; \
	    [ -z "$$need" ] || { sudo=; [ "$$(id -u)" = 0 ] || sudo=sudo; \
	    $$sudo apt-get update -qq && \
	    DEBIAN_FRONTEND=noninteractive $$sudo apt-get install -y -qq --no-install-recommends $$need; }
	$(CMAKE) -S . -B $(CLANG_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=clang \
	    -DCMAKE_C_FLAGS=-march=native -DSPRINGMASS_BUILD_FMU=OFF $(CMAKE_FLAGS)
	$(CMAKE) --build $(CLANG_DIR) -j $(JOBS) --target test_forces test_jacobian test_vector_ops
	$(CTEST) --test-dir $(CLANG_DIR) --output-on-failure -j $(JOBS) -R '^(forces|jacobian|vector_ops)$$'

# The library, the tool, the tests and the examples with link-time optimisation, as distributions
# build C libraries (-flto=auto -ffat-lto-objects), and without the FMU runtime (the library and
# the tool alone, as the README builds them for embedding): every link with -Wall -Wextra -Werror,
# where GCC reports the warnings of code it inlines across files, then the whole suite.
$(LTO_DIR)/build.ninja: $(CONFIGURE_FLAGS_AGAIN) | setup
	$(CMAKE) -S . -B $(LTO_DIR) -G Ninja -DCMAKE_BUILD_TYPE=Release -DSPRINGMASS_BUILD_FMU=OFF \
	    "-DCMAKE_C_FLAGS=-flto=auto -ffat-lto-objects" "-DCMAKE_EXE_LINKER_FLAGS=-Wall -Wextra -Werror" \
	    -DSPRINGMASS_PYTHON=$(PYTHON_ARG) $(CMAKE_FLAGS)

test-lto: setup $(LTO_DIR)/build.ninja
	$(CMAKE) --build $(LTO_DIR) -j $(JOBS)
	$(CTEST) --test-dir $(LTO_DIR) --output-on-failure -j $(JOBS)

bench-forces: build
	bench/bench_forces.sh $(BUILD_DIR)

bench-cloth: build
	QUICK=$(QUICK) LONG=$(LONG) bench/bench_cloth.sh $(BUILD_DIR)

fuzz: setup
	fuzz/run.sh $(FUZZ_SECONDS) $(FUZZ_TARGETS)

# Installs headers, library, tool, FMU runtime and CMake package under PREFIX (default /usr/local).
PREFIX ?= /usr/local
install: build
	$(CMAKE) --install $(BUILD_DIR) --prefix $(PREFIX)

clean:
	rm -rf $(BUILD_DIR) $(SANITIZE_DIR) $(TSAN_DIR) $(CLANG_DIR) $(LTO_DIR)
