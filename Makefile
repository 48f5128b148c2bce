# The project's commands. Every target first runs the idempotent setup (apt, venv, catkin_make).
#   make mission   run the Challenge 3 mission in simulation (headless)  SEED= UAVS= RTF= RECORD=1 SUMMARY=
#   make test      run every test (pytest unit tests + rostest integration tests)      PKGS="smach ual_sim"
#   make bench     run the benchmarks, write bench/results/latest.json
SHELL := /bin/bash
SEED ?= 1
UAVS ?= 3
RTF ?= 4
RECORD ?= 0
SUMMARY ?=
PKGS ?=

.PHONY: setup build mission test bench lint clean
setup:
	@bash setup/setup.sh

build: setup

mission: setup
	@bash tools/run_mission.sh SEED=$(SEED) UAVS=$(UAVS) RTF=$(RTF) RECORD=$(RECORD) SUMMARY=$(SUMMARY)

test: setup
	@bash tools/run_tests.sh $(PKGS)

bench: setup
	@bash tools/run_bench.sh

lint: setup
	@source env.sh && cd catkin_ws && catkin_lint -W2 --strict src

clean:
	rm -rf catkin_ws/build catkin_ws/devel .setup-stamps test_results
