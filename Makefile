# The project's commands. Every target first runs the idempotent setup (apt, venv, catkin_make).
#   make mission   run the Challenge 3 mission in simulation (headless)  SEED= UAVS= RTF= RECORD=1 SUMMARY=
#                  UNCERTAINTY=realistic (GNSS error and none indoors, unknown water and heat, laser dropouts;
#                  default ideal)  GNSS_DENIED_INDOORS=0|1 (default: as the uncertainty profile says)
#                  INDOOR_SLAM=0|1 (hector_mapping + the anchored indoor pose on the robots that go indoors;
#                  default: on wherever GNSS is denied indoors)  INDOOR_SEARCH=explore|plan  WORLD=path.yaml
#                  GCS=0 (no web ground station; it is on http://127.0.0.1:8088/ by default)  GCS_PORT=
#   make replay BAG=results/.../mission.bag   replay a recorded trial on the ground station page  GCS_PORT=
#                  (without BAG: the page lists the recordings under results/ to pick one)
#   make test      run every test (pytest unit tests + rostest integration tests + the short fault suite)
#                  PKGS="smach ual_sim"   SKIP_FAULTS=1 (no fault suite)
#   make bench     run the benchmarks, write bench/results/latest.json
#   make test-faults  fuzz every node, then the mission on network-namespace hosts with link cuts and
#                  kill -9 (root; a few minutes), report in results/robustness/report.json  SEED= UAVS= RTF=
SHELL := /bin/bash
SEED ?= 1
UAVS ?= 3
RTF ?= 4
RECORD ?= 0
RECORD_SLAM ?= 0
SUMMARY ?=
PKGS ?=
GCS ?= 1
GCS_PORT ?= 8088
BAG ?=
UNCERTAINTY ?= ideal
INDOOR_SLAM ?=
GNSS_DENIED_INDOORS ?=
WORLD ?=
INDOOR_SEARCH ?= explore

.PHONY: setup build mission replay test test-faults bench lint clean
setup:
	@bash setup/setup.sh

build: setup

mission: setup
	@bash tools/run_mission.sh SEED=$(SEED) UAVS=$(UAVS) RTF=$(RTF) RECORD=$(RECORD) RECORD_SLAM=$(RECORD_SLAM) SUMMARY=$(SUMMARY) \
	  GCS=$(GCS) GCS_PORT=$(GCS_PORT) UNCERTAINTY=$(UNCERTAINTY) INDOOR_SLAM=$(INDOOR_SLAM) \
	  GNSS_DENIED_INDOORS=$(GNSS_DENIED_INDOORS) WORLD=$(WORLD) INDOOR_SEARCH=$(INDOOR_SEARCH)

replay: setup
	@source env.sh && rosrun mbzirc_ground_station replay $(if $(BAG),"$(BAG)") --port $(GCS_PORT)

test: setup
	@bash tools/run_tests.sh $(PKGS)

# The long version of the fault step of `make test` (which runs a short schedule): the fuzz rostests again,
# then a whole 600 s mission with the faults (about 5 minutes at RTF 4). Needs root for ip netns.
test-faults: setup
	@mkdir -p results/robustness && source env.sh && for t in fuzz_project_nodes fuzz_mission_nodes fuzz_ugv_recorder_nodes; do \
	    echo "fuzzing every input of the nodes of $$t.test"; \
	    unshare -n sh -c "ip link set lo up; exec rostest mbzirc_robustness $$t.test" \
	      > results/robustness/$$t.log 2>&1 || echo "fuzz: $$t FAILED, see results/robustness/$$t.log"; done; \
	  rosrun mbzirc_robustness fault_suite --seed $(SEED) --uavs $(UAVS) --rtf $(RTF)

bench: setup
	@bash tools/run_bench.sh

lint: setup
	@source env.sh && cd catkin_ws && catkin_lint -W2 --strict src

clean:
	rm -rf catkin_ws/build catkin_ws/devel .setup-stamps test_results
