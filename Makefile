# The two commands a user needs: `make demo` and `make test`. Both install the Debian
# dependencies first (scripts/install-deps is idempotent and quick when all is present).
#
# Debian's python3 must come first: a pyenv python3 on PATH breaks catkin and rospy.
export PATH := /usr/bin:/bin:$(PATH)
BUILD_DIR ?= build
# catkin's devel space (executables, generated messages, setup.bash) sits beside the source,
# not inside build/: rosrun skips every path below <package>/build/. `source devel/setup.bash`
# then makes rosrun, roslaunch, rosmsg and rostopic find the package.
DEVEL_DIR ?= $(abspath devel)
# The other build folders live below build/, so rosrun never sees a second copy of a node.
ASAN_BUILD_DIR ?= build/asan
JOBS ?= $(shell nproc)
PROBLEMS_DIR ?= $(abspath ../shared/problems)
# rosout and roslaunch write their logs inside the build folder, not in $HOME.
export ROS_HOME := $(abspath $(BUILD_DIR))/ros_home
export ROS_LOG_DIR := $(ROS_HOME)/log

.PHONY: all deps configure build test test-asan fuzz demo bench soak stabilization clean \
        bench-runtime bench-runtime-configure effects-cost scaling latency

all: build

deps:
	@scripts/install-deps

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release -DCATKIN_DEVEL_PREFIX=$(DEVEL_DIR)

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)
	cmake --build $(BUILD_DIR) -j$(JOBS) --target tests

# Builds everything including tests, runs them all with ctest (catkin's `run_tests`
# exits 0 on failure, so it is not used), and fails on any failure.
# Then the AddressSanitizer/UBSan pass (test-asan) in its own build folder; SANITIZE=0 skips
# it (a clean clone: 19 min on 2 loaded cores here, most of it compiling).
SANITIZE ?= 1
test: build
	@mkdir -p $(ROS_LOG_DIR)
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j$(JOBS)
	@if [ "$(SANITIZE)" = "1" ]; then $(MAKE) --no-print-directory test-asan; fi

# The unit tests that need no roscore, once more under AddressSanitizer + UndefinedBehavior-
# Sanitizer (LCS_SANITIZE=ON) in their own build folder; any sanitizer report fails the run
# (halt_on_error, leaks included). RelWithDebInfo at -O1 -g1: Debug is ~30x slower on the
# solver tests, and -O2 -g doubles the compile time of this pass for little run time.
ASAN_TESTS ?= test_core test_problem_io test_scene test_ros_msg_conversion test_scene_msg_conversion \
              test_replay test_hard_cases test_adversarial_input test_fuzz_corpus
ASAN_OPTIONS_TEST ?= detect_leaks=1:halt_on_error=1
UBSAN_OPTIONS_TEST ?= halt_on_error=1:print_stacktrace=1
test-asan:
	cmake -S . -B $(ASAN_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DLCS_SANITIZE=ON \
	  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG"
	cmake --build $(ASAN_BUILD_DIR) -j$(JOBS) --target $(ASAN_TESTS)
	@mkdir -p $(abspath $(ASAN_BUILD_DIR))/ros_home/log
	ROS_HOME=$(abspath $(ASAN_BUILD_DIR))/ros_home ROS_LOG_DIR=$(abspath $(ASAN_BUILD_DIR))/ros_home/log \
	ASAN_OPTIONS=$(ASAN_OPTIONS_TEST) UBSAN_OPTIONS=$(UBSAN_OPTIONS_TEST) \
	  ctest --test-dir $(ASAN_BUILD_DIR) --output-on-failure -j$(JOBS) \
	    -R '_gtest_($(shell echo $(ASAN_TESTS) | tr ' ' '|'))$$'

# Fuzzing with clang's libFuzzer (not part of make test): builds the two targets of
# test/fuzz/ (the .dat reader; message → problem → solve) with ASan + UBSan in
# FUZZ_BUILD_DIR and runs each for FUZZ_SECONDS on the seeds of test/fuzz/corpus/<target>.
# New inputs go to FUZZ_BUILD_DIR/corpus/<target>, crash inputs to FUZZ_BUILD_DIR/artifacts/;
# a crash fails the target (fix it, then add the input to test/fuzz/corpus/<target>/, which
# test_fuzz_corpus replays in make test).
FUZZ_BUILD_DIR ?= build/fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= dat_reader msg_solve
fuzz:
	@scripts/install-deps fuzz
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DLCS_SANITIZE=ON -DLCS_FUZZ=ON
	cmake --build $(FUZZ_BUILD_DIR) -j$(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	@for t in $(FUZZ_TARGETS); do \
	  mkdir -p $(FUZZ_BUILD_DIR)/corpus/$$t $(FUZZ_BUILD_DIR)/artifacts || exit 1; \
	  echo "== fuzz_$$t: $(FUZZ_SECONDS) s"; \
	  ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
	  $(FUZZ_BUILD_DIR)/devel/lib/lcp_contact_solver/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) \
	    -max_len=4096 -timeout=20 -rss_limit_mb=2048 -print_final_stats=1 \
	    -artifact_prefix=$(FUZZ_BUILD_DIR)/artifacts/$$t- \
	    $(FUZZ_BUILD_DIR)/corpus/$$t test/fuzz/corpus/$$t || exit 1; \
	done

# Part 1: every shared problem through lcp_solve (a table, seconds). Part 2: the solver node
# and the example simulator in closed loop on a scene (scripts/run-demo: starts roscore if no
# master runs, ~10 s, a line per simulated second and the final body states, then stops
# everything it started). DEMO_ARGS are demo.launch arguments, e.g.
#   make demo DEMO_ARGS="scene:=incline duration:=5"
DEMO_ARGS ?=
# Builds only what the demo runs (the tests are built by `make test`).
DEMO_TARGETS = lcp_solve contact_solver_node scene_simulator
demo: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target $(DEMO_TARGETS)
	@echo "== Part 1: the shared problems, solved by lcp_solve =="
	$(DEVEL_DIR)/lib/lcp_contact_solver/lcp_solve $(PROBLEMS_DIR)/lcp/*.dat $(PROBLEMS_DIR)/fc3d/*
	@echo
	@echo "== Part 2: contact solver node + scene simulator (ROS, simulated time) =="
	BUILD_DIR=$(abspath $(BUILD_DIR)) DEVEL_DIR=$(DEVEL_DIR) DEMO_ARGS="$(DEMO_ARGS)" scripts/run-demo

# The benchmark study (docs/BENCHMARKS.md): installs the optional peer/plotting packages,
# builds bench/work_precision in its own folder, runs every solver and peer on every problem
# (about 12 minutes on 2 cores) and redraws docs/figures/*.png and the tables in
# docs/BENCHMARKS.md. Not part of `make test`. BENCH_ARGS passes options (e.g. --quick).
BENCH_BUILD_DIR ?= build/bench-study
BENCH_CSV ?= bench/results/work_precision.csv
BENCH_ARGS ?=
bench:
	@scripts/install-deps bench
	cmake -S . -B $(BENCH_BUILD_DIR) -DCMAKE_BUILD_TYPE=Release
	cmake --build $(BENCH_BUILD_DIR) -j$(JOBS) --target work_precision
	@mkdir -p $(dir $(BENCH_CSV))
	$(BENCH_BUILD_DIR)/devel/lib/lcp_contact_solver/work_precision --out $(BENCH_CSV) $(BENCH_ARGS)
	/usr/bin/python3 bench/plot_work_precision.py $(BENCH_CSV)

# The soak benchmark (docs/BENCHMARKS.md "Soak", issue #7): contact_solver_node fed from
# test/data/box_stack.bag at 1 kHz for 5 minutes by bench/soak_feeder.cpp, its RSS sampled
# each second into bench/results/soak_rss_box_stack.csv (and .log), then a summary. Builds
# only the two executables, in BUILD_DIR. Not part of `make test`. SOAK_ARGS passes options:
#   make soak SOAK_ARGS="--bag test/data/mixed.bag --duration 60 --param queue_size=100"
SOAK_ARGS ?=
soak: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target contact_solver_node soak_feeder
	bench/soak.sh --build $(BUILD_DIR) $(SOAK_ARGS)

# What erp and softness cost in iterations and buy in depth (docs/SOLVERS.md "Penetration
# correction and softness"; the figures in docs/BENCHMARKS.md): in-process, no ROS graph.
stabilization: configure
	cmake --build $(BUILD_DIR) -j$(JOBS) --target stabilization_tradeoff
	@mkdir -p bench/results
	$(DEVEL_DIR)/lib/lcp_contact_solver/stabilization_tradeoff --out bench/results/stabilization.csv

# Runtime benchmarks (docs/BENCHMARKS.md "Paying only for what a scene uses", "Scaling",
# "Latency and rate"): in-process effect costs and scaling, then the live node/nodelet round
# trip (bench/latency.sh: private roscore, stops what it starts). Built in BENCH_RUNTIME_BUILD_DIR
# (only these targets); CSVs in bench/results/. Not part of `make test`. Each can run alone:
#   make effects-cost EFFECTS_ARGS="--bases 5 --balls 40"   make scaling SCALING_ARGS="--bases 2,5 --balls 4,40"
#   make latency LATENCY_ARGS="--modes node --count 100"
BENCH_RUNTIME_BUILD_DIR ?= build/bench-runtime
BENCH_RUNTIME_BIN = $(BENCH_RUNTIME_BUILD_DIR)/devel/lib/lcp_contact_solver
EFFECTS_ARGS ?=
SCALING_ARGS ?=
LATENCY_ARGS ?=
bench-runtime: effects-cost scaling latency

bench-runtime-configure:
	@scripts/install-deps
	cmake -S . -B $(BENCH_RUNTIME_BUILD_DIR) -DCMAKE_BUILD_TYPE=Release

effects-cost: bench-runtime-configure
	cmake --build $(BENCH_RUNTIME_BUILD_DIR) -j$(JOBS) --target effects_cost
	@mkdir -p bench/results
	$(BENCH_RUNTIME_BIN)/effects_cost --out bench/results/effects_cost.csv $(EFFECTS_ARGS) >bench/results/effects_cost.log
	@cat bench/results/effects_cost.log

scaling: bench-runtime-configure
	cmake --build $(BENCH_RUNTIME_BUILD_DIR) -j$(JOBS) --target scaling_bench
	@mkdir -p bench/results
	$(BENCH_RUNTIME_BIN)/scaling_bench --out bench/results/scaling.csv $(SCALING_ARGS) >bench/results/scaling.log
	@cat bench/results/scaling.log

latency: bench-runtime-configure
	cmake --build $(BENCH_RUNTIME_BUILD_DIR) -j$(JOBS) --target latency_bench
	bench/latency.sh --build $(BENCH_RUNTIME_BUILD_DIR) $(LATENCY_ARGS)

clean:
	rm -rf $(BUILD_DIR) $(DEVEL_DIR)
