# FMU: packaging, tests (C host, fmpy) and demo/benchmark steps. Included by the top-level Makefile.
#   make fmu            target/fmu/bistable_impact.fmu (release build, packaged once)
#   make test-fmu       C host (cbindgen header, dlopen) + fmpy validate + pytest tests/fmu
#   make fmu-reference  regenerate the co-simulation regression CSVs in tests/fmu/reference/
#   make fmu-guid       rewrite the guid of modelDescription.xml after editing it
#   make fmu-bench      cost per fmi2DoStep (C host) and fmpy simulate wall time

FMU_NAME := bistable_impact
FMU_DIR := target/fmu
FMU := $(FMU_DIR)/$(FMU_NAME).fmu
FMU_STAGE := $(FMU_DIR)/stage
FMU_SO := $(FMU_STAGE)/binaries/linux64/$(FMU_NAME).so
FMU_HOST := $(FMU_DIR)/host
VENV_PY := .venv/bin/python

.PHONY: fmu test-fmu fmu-host fmu-reference fmu-guid fmu-bench fmu-demo

TEST_TARGETS += test-fmu
DEMO_TARGETS += fmu fmu-demo

fmu:
	$(CARGO) build --release -p bistable-fmu
	rm -rf $(FMU_STAGE) && mkdir -p $(FMU_STAGE)/binaries/linux64 $(FMU_STAGE)/documentation $(FMU_STAGE)/extra
	cp modelDescription.xml $(FMU_STAGE)/
	cp target/release/lib$(FMU_NAME).so $(FMU_SO)
	strip --strip-debug $(FMU_SO)
	cp fmu/documentation/index.html $(FMU_STAGE)/documentation/
	cp $(wildcard tests/fmu/reference/*.csv) tests/fmu/reference/README.md $(FMU_STAGE)/extra/
	rm -f $(FMU)
	cd $(FMU_STAGE) && python3 -m zipfile -c ../$(FMU_NAME).fmu modelDescription.xml binaries documentation extra
	@echo "fmu: $(FMU)"

$(FMU_HOST): tests/fmu_host/host.c fmu/include/$(FMU_NAME).h
	mkdir -p $(FMU_DIR)
	$(CC) -std=gnu11 -O2 -Wall -Wextra -Werror -Ifmu/include $< -o $@ -ldl -lm

fmu-host: $(FMU_HOST)

test-fmu: setup fmu fmu-host
	$(CARGO) build --release -p bistable-cli
	$(FMU_HOST) test $(FMU_SO) modelDescription.xml
	.venv/bin/fmpy validate $(FMU)
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
