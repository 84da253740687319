# FMU: packaging, tests (C host, fmpy) and demo/benchmark steps. Included by the top-level Makefile.
#   make fmu            target/fmu/bistable_impact.fmu (FMI 2.0) and bistable_impact_fmi3.fmu (FMI 3.0):
#                       one release build of the binary, which exports both APIs; the FMI 3.0
#                       modelDescription.xml is generated from the FMI 2.0 one
#   make test-fmu       C host (cbindgen header, dlopen) + fmpy validate (both FMUs) + pytest tests/fmu
#   make fmu-reference  regenerate the co-simulation regression CSVs in tests/fmu/reference/
#   make fmu-guid       rewrite the guid of modelDescription.xml after editing it
#   make fmu-bench      cost per communication step in FMI 2.0/3.0 CS and ME host loops (C host:
#                       bare step, + Get(x, v), + Set(z_in, zdot_in), sampled inputs) and fmpy
#   make stress-fmu     fault campaign (part of make stress): C host fuzz mode over FUZZ_SEEDS x
#                       FUZZ_CALLS, valgrind memcheck (host test + VALGRIND_SEEDS x VALGRIND_CALLS),
#                       cargo-fuzz targets for FUZZ_SECONDS each
#                       FMI 3.0 host (host3): fuzz FUZZ3_SEEDS x FUZZ3_CALLS, valgrind memcheck
#                       (host3 test + VALGRIND3_SEEDS x VALGRIND3_CALLS)
#   make fmu-host3      the FMI 3.0 C host target/fmu/host3 (tests/fmu_host/fmi3, official headers)

FMU_NAME := bistable_impact
FMU_DIR := target/fmu
FMU := $(FMU_DIR)/$(FMU_NAME).fmu
FMU_STAGE := $(FMU_DIR)/stage
FMU_SO := $(FMU_STAGE)/binaries/linux64/$(FMU_NAME).so
FMU3 := $(FMU_DIR)/$(FMU_NAME)_fmi3.fmu
FMU3_STAGE := $(FMU_DIR)/stage3
FMU_HOST := $(FMU_DIR)/host
VENV_PY := .venv/bin/python
# Quick fuzz run in test-fmu (under a second) and the long campaign of stress-fmu.
FMU_FUZZ_QUICK := 1-20 5000
FUZZ_SEEDS ?= 1-200
FUZZ_CALLS ?= 20000
VALGRIND_SEEDS ?= 1-10
VALGRIND_CALLS ?= 20000
FUZZ_SECONDS ?= 300
# FMI 3.0 C host (tests/fmu_host/fmi3): compiled against the official FMI 3.0 headers shipped with
# fmpy (fmi3Functions.h, fmi3FunctionTypes.h, fmi3PlatformTypes.h; fmi2FunctionTypes.h for the
# comparison with the FMI 2.0 functions of the same binary), run on the FMI 3.0 FMU's binary and
# generated modelDescription.xml. Quick fuzz in test-fmu (seconds), >= 1e6 calls in stress-fmu.
FMU_HOST3 := $(FMU_DIR)/host3
FMU3_SO := $(FMU3_STAGE)/binaries/x86_64-linux/$(FMU_NAME).so
FMU3_MD := $(FMU3_STAGE)/modelDescription.xml
FMI_C_HEADERS = $(shell $(VENV_PY) -c "import fmpy,os;print(os.path.join(os.path.dirname(fmpy.__file__),'c-code'))")
FMU_HOST3_SRC := tests/fmu_host/fmi3/host3.c tests/fmu_host/fmi3/fuzz3.c
FMU_FUZZ3_QUICK := 1-20 5000
FUZZ3_SEEDS ?= 1-200
FUZZ3_CALLS ?= 5000
VALGRIND3_SEEDS ?= 1-5
VALGRIND3_CALLS ?= 5000

.PHONY: fmu test-fmu fmu-host fmu-reference fmu-guid fmu-bench fmu-demo stress-fmu fmu-host3

TEST_TARGETS += test-fmu
DEMO_TARGETS += fmu fmu-demo
STRESS_TARGETS += stress-fmu

fmu: setup
	$(CARGO) build --release -p bistable-fmu
	rm -rf $(FMU_STAGE) && mkdir -p $(FMU_STAGE)/binaries/linux64 $(FMU_STAGE)/documentation $(FMU_STAGE)/extra
	cp modelDescription.xml $(FMU_STAGE)/
	cp target/release/lib$(FMU_NAME).so $(FMU_SO)
	strip --strip-debug $(FMU_SO)
	cp fmu/documentation/index.html $(FMU_STAGE)/documentation/
	cp $(wildcard tests/fmu/reference/*.csv) tests/fmu/reference/README.md $(FMU_STAGE)/extra/
	rm -f $(FMU)
	cd $(FMU_STAGE) && python3 -m zipfile -c ../$(FMU_NAME).fmu modelDescription.xml binaries documentation extra
	rm -rf $(FMU3_STAGE) && mkdir -p $(FMU3_STAGE)/binaries/x86_64-linux $(FMU3_STAGE)/documentation
	target/release/fmi3-model-description > $(FMU3_STAGE)/modelDescription.xml
	cp $(FMU_SO) $(FMU3_STAGE)/binaries/x86_64-linux/
	cp fmu/documentation/index.html $(FMU3_STAGE)/documentation/
	rm -f $(FMU3)
	cd $(FMU3_STAGE) && python3 -m zipfile -c ../$(FMU_NAME)_fmi3.fmu modelDescription.xml binaries documentation
	@echo "fmu: $(FMU) $(FMU3)"

FMU_HOST_SRC := tests/fmu_host/host.c tests/fmu_host/me.c tests/fmu_host/fuzz.c tests/fmu_host/bench.c
$(FMU_HOST): $(FMU_HOST_SRC) tests/fmu_host/host.h tests/fmu_host/md_text.h tests/fmu_host/fuzzkit.h fmu/include/$(FMU_NAME).h
	mkdir -p $(FMU_DIR)
	$(CC) -std=gnu11 -O2 -g -Wall -Wextra -Werror -Ifmu/include $(FMU_HOST_SRC) -o $@ -ldl -lm

fmu-host: $(FMU_HOST)

$(FMU_HOST3): $(FMU_HOST3_SRC) tests/fmu_host/fmi3/host3.h tests/fmu_host/md_text.h tests/fmu_host/fuzzkit.h
	mkdir -p $(FMU_DIR)
	@test -f "$(FMI_C_HEADERS)/fmi3Functions.h" || { echo "fmi3Functions.h not found (fmpy c-code: '$(FMI_C_HEADERS)')"; exit 1; }
	$(CC) -std=gnu11 -O2 -g -Wall -Wextra -Werror -I"$(FMI_C_HEADERS)" $(FMU_HOST3_SRC) -o $@ -ldl -lm

fmu-host3: setup $(FMU_HOST3)

test-fmu stress-fmu: fmu-host3

test-fmu: setup fmu fmu-host
	$(CARGO) build --release -p bistable-cli
	$(FMU_HOST) test $(FMU_SO) modelDescription.xml
	FUZZ_QUIET=1 $(FMU_HOST) fuzz $(FMU_SO) modelDescription.xml $(FMU_FUZZ_QUICK)
	$(FMU_HOST3) test $(FMU3_SO) $(FMU3_MD)
	FUZZ_QUIET=1 $(FMU_HOST3) fuzz $(FMU3_SO) $(FMU3_MD) $(FMU_FUZZ3_QUICK)
	.venv/bin/fmpy validate $(FMU)
	.venv/bin/fmpy validate $(FMU3)
	$(VENV_PY) -m pytest -q tests/fmu

fmu-reference: setup fmu
	$(VENV_PY) tests/fmu/regenerate.py

fmu-guid:
	python3 fmu/guid.py

fmu-bench: setup fmu fmu-host
	$(FMU_HOST) bench $(FMU_SO) modelDescription.xml
	$(VENV_PY) tests/fmu/bench_fmpy.py $(FMU)

fmu-demo: setup fmu
	mkdir -p $(OUT)
	.venv/bin/fmpy validate $(FMU)
	.venv/bin/fmpy simulate $(FMU) --output-interval 0.01 --output-file $(OUT)/fmu_baseline.csv
	@echo "fmu-demo: $(OUT)/fmu_baseline.csv (paper baseline through the FMU, default experiment)"

## The FMU part of the stress and fault campaign (docs/reliability.md): random FMI call sequences
## with invariants (tests/fmu_host/fuzz.c), valgrind memcheck, coverage-guided fuzzing (fmu/fuzz).
stress-fmu: setup fmu fmu-host
	FUZZ_QUIET=1 $(FMU_HOST) fuzz $(FMU_SO) modelDescription.xml $(FUZZ_SEEDS) $(FUZZ_CALLS)
	bash fmu/valgrind.sh $(FMU_HOST) target/release/lib$(FMU_NAME).so $(VALGRIND_SEEDS) $(VALGRIND_CALLS)
	FUZZ_QUIET=1 $(FMU_HOST3) fuzz $(FMU3_SO) $(FMU3_MD) $(FUZZ3_SEEDS) $(FUZZ3_CALLS)
	bash fmu/valgrind.sh $(FMU_HOST3) target/release/lib$(FMU_NAME).so $(VALGRIND3_SEEDS) $(VALGRIND3_CALLS) $(FMU3_MD)
	bash fmu/fuzz/run.sh $(FUZZ_SECONDS)
	@echo "stress-fmu: passed"
