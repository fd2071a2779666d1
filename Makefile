# The two commands a user needs: `make demo` and `make test`. Both install the Debian
# dependencies first (scripts/install-deps is idempotent and quick when all is present).
#
# Debian's python3 must come first: a pyenv python3 on PATH breaks catkin and rospy.
export PATH := /usr/bin:/bin:$(PATH)
BUILD_DIR ?= build
ASAN_BUILD_DIR ?= build-asan
JOBS ?= $(shell nproc)
PROBLEMS_DIR ?= $(abspath ../shared/problems)
# rosout and roslaunch write their logs inside the build folder, not in $HOME.
export ROS_HOME := $(abspath $(BUILD_DIR))/ros_home
export ROS_LOG_DIR := $(ROS_HOME)/log

.PHONY: all deps configure build test demo clean

all: build

deps:
	@scripts/install-deps

configure: deps
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release

build: configure
	cmake --build $(BUILD_DIR) -j$(JOBS)
	cmake --build $(BUILD_DIR) -j$(JOBS) --target tests

# Builds everything including tests, runs them all with ctest (catkin's `run_tests`
# exits 0 on failure, so it is not used), and fails on any failure.
test: build
	@mkdir -p $(ROS_LOG_DIR)
	ctest --test-dir $(BUILD_DIR) --output-on-failure -j$(JOBS)

demo: build
	$(BUILD_DIR)/devel/lib/lcp_contact_solver/lcp_solve $(PROBLEMS_DIR)/lcp/*.dat $(PROBLEMS_DIR)/fc3d/*

clean:
	rm -rf $(BUILD_DIR) $(ASAN_BUILD_DIR)
