# Makefile -- thin wrapper over CMake. `make run` and `make test` do all set-up on a fresh Debian 12:
# they install missing packages (apt-get; sudo only when not root), configure, build, then run.
.PHONY: all deps web-deps build run still test test-deploy test-cluster bench fuzz soak docs format format-check clean

BUILD      ?= build
TEST_BUILD ?= build-asan
JOBS       ?= $(shell nproc)
# ctest runs one test more than there are cores: the browser and daemon tests wait on sockets and
# frames (under half a core each when two run together), and the spare slot fills those waits.
TEST_JOBS  ?= $(shell echo $$(( $$(nproc) + 1 )))
SUDO       := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

# Every Debian package the build, the tests and the tools need.
PACKAGES := build-essential cmake pkg-config git clang-format \
            libembree-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev \
            libwebsockets-dev libssl-dev libcap-dev zlib1g-dev \
            libassimp-dev libcjson-dev libturbojpeg0-dev libopenexr-dev libpng-dev \
            libcmocka-dev ffmpeg openssl haproxy python3 python3-matplotlib python3-websockets python3-pil chromium \
            clang libclang-rt-14-dev libomp-14-dev
# Node.js and npm only where no node/npm is on the PATH: a machine may have its own, and Debian's npm
# installed over another npm can break it.
NODE_PACKAGES := $(shell command -v node >/dev/null || echo nodejs) \
                 $(shell command -v npm >/dev/null || echo npm)

all: build

deps:
	@missing=$$(for p in $(PACKAGES) $(NODE_PACKAGES); do \
	    dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	    echo "Installing: $$missing"; \
	    $(SUDO) apt-get update -qq && \
	    DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi

# The web client's npm packages (package-lock.json: uPlot, and playwright-core for the browser
# test): `npm ci` when node_modules is missing or older than the lock file, then uPlot into
# web/vendor/ (not in git), where iird's mount of web/ serves it.
web-deps: deps
	@if [ ! -d node_modules ] || [ package-lock.json -nt node_modules ]; then \
	    npm ci --no-audit --no-fund && touch node_modules; fi
	@mkdir -p web/vendor/uplot
	cp node_modules/uplot/dist/uPlot.esm.js node_modules/uplot/dist/uPlot.min.css web/vendor/uplot/

build: deps web-deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DIIR_WERROR=ON >/dev/null
	cmake --build $(BUILD) -j $(JOBS)

# The main job: the daemon on the built-in Cornell box; it prints the URL to open. Ctrl-C stops it.
run: build
	$(BUILD)/iird serve

# One path-traced still of the built-in Cornell box.
still: build
	mkdir -p out
	$(BUILD)/iird render --method pt --spp 256 --bounces 2 --size 512x512 --out out/cornell.png
	@echo "Wrote out/cornell.png (open it in an image viewer)."

# Sanitizer build (ASan + UBSan) and the whole suite through ctest, plus the format check.
test: deps web-deps format-check
	cmake -S . -B $(TEST_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIIR_WERROR=ON \
	    -DIIR_SANITIZE=address,undefined >/dev/null
	cmake --build $(TEST_BUILD) -j $(JOBS)
	cd $(TEST_BUILD) && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
	    ctest --output-on-failure -j $(TEST_JOBS)

# Three daemons behind a real HAProxy from deploy/haproxy.cfg, on loopback (docs/deploy.md); also
# part of `make test` (about 10 s).
test-deploy: build
	cd $(BUILD) && ctest -R integration_test_deploy --output-on-failure

# The offline half of docs/deploy.md on a real one-node Slurm cluster started in a temporary
# directory (tests/cluster/test_cluster.sh; about 40 s). Not part of `make test`: it installs
# Debian's slurm-wlm and munge first. Exit 77 from the script (Slurm cannot start here) is reported
# as a skip.
CLUSTER_PACKAGES := slurm-wlm munge
test-cluster: build
	@missing=$$(for p in $(CLUSTER_PACKAGES); do \
	    dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q 'install ok installed' || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	    echo "Installing: $$missing"; \
	    DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq --no-install-recommends $$missing; \
	fi
	@bash tests/cluster/test_cluster.sh $(BUILD)/iird . ; rc=$$?; \
	if [ $$rc = 77 ]; then echo "test-cluster: skipped (see the SKIP line above)"; exit 0; fi; exit $$rc

# Benchmarks (not tests; docs/experiments.md reads them): ray rates, then `iird bench` over the
# standard set -- the Cornell box orbit with every method (a VPL sweep for iir, ir and ism, pt at
# 1/4/16 spp: the time-against-error chart), its stress paths, the conference room's orbit, and
# multiresolution shading (full against multires at 512x384, and at the paper's 1024x768), the
# classics (radiosity at three patch sizes beside ir and iir against 8-bounce references; iir and
# ir at 2, 4 and 8 bounces; whitted,
# hybrid, radiosity and pt on the mirror/glass box; radiosity's form-factor time and cache load at
# each patch size), the shading phases (issue 31: Cornell and conference at 512x384 and 1024x768,
# full and multires; each instruction set of the kernels, IIR_ISA; images of the scalar and the
# AVX2 kernels against the same references, out/bench/shading/) -- each
# with references (cached in $(REFCACHE): a second run skips them), frames.csv, summary.json and
# charts in out/bench/<scene>-<path>/. Measured: 6 min 44 s on 2 quiet cores with the references
# already cached (2026-11-25); with an empty cache their rendering comes on top (not timed).
REFCACHE ?= out/refcache
BENCH     = $(BUILD)/iird bench --ref-cache $(REFCACHE)
STRESS    = sweep-fast corner grazing void
PEERS     = iir,ir,rsm,ism,hier
bench: build
	mkdir -p out/bench/cornell-orbit out/bench/conference-orbit out/bench/cornell-multires \
	    out/bench/cornell-multires-1024 out/bench/conference-multires-1024 \
	    $(foreach p,teleport occluder $(STRESS),out/bench/cornell-$(p)) \
	    out/bench/cornell-classics out/bench/cornell-spheres out/bench/cornell-bounces \
	    out/bench/cornell-compensation out/bench/cornell-controller out/bench/material-room \
	    out/bench/glossy-spheres out/bench/glossy-room out/bench/glossy-vsl \
	    out/bench/glossy-flicker/cornell_spheres out/bench/glossy-flicker/material_room \
	    out/bench/refill out/bench/shading
	$(BUILD)/iird raybench conference
	$(BUILD)/iird raybench
	$(BENCH) --anim orbit --frames 0:100 --size 320x240 --methods $(PEERS),pt \
	    --sweep vpls=64,256,1024 --sweep spp=1,4,16 --ref-spp 1024 --ref-every 25 \
	    --out out/bench/cornell-orbit
	$(foreach p,teleport occluder,$(BENCH) --anim $(p) --size 256x192 --methods $(PEERS) \
	    --ref-spp 128 --ref-every 10 --out out/bench/cornell-$(p) &&) true
	$(foreach p,$(STRESS),$(BENCH) --anim $(p) --size 256x192 --methods $(PEERS) \
	    --ref-spp 64 --ref-every 2 --out out/bench/cornell-$(p) &&) true
	$(BENCH) conference --anim orbit --size 320x240 --methods $(PEERS) --ref-spp 256 \
	    --ref-every 100 --out out/bench/conference-orbit
	$(BENCH) --anim orbit --frames 0:50 --size 512x384 --methods iir,ir,rsm \
	    --sweep shading=full,multires --ref-spp 256 --ref-every 25 --out out/bench/cornell-multires
	$(BENCH) --anim orbit --frames 0:60 --size 1024x768 --methods iir --sweep shading=full,multires \
	    --ref-spp 0 --out out/bench/cornell-multires-1024
	$(BENCH) conference --anim orbit --frames 0:60 --size 1024x768 --methods iir \
	    --sweep shading=full,multires --ref-spp 0 --out out/bench/conference-multires-1024
	$(BENCH) material_room --anim orbit --frames 0:60 --size 512x384 --methods $(PEERS) \
	    --ref-spp 256 --ref-every 30 --out out/bench/material-room
	$(BENCH) --anim orbit --frames 0:100 --size 320x240 --methods radiosity,ir,iir --bounces 8 \
	    --sweep patch_area=0.008,0.002,0.0005 --sweep direct=pixels,patches --ref-spp 512 \
	    --ref-every 25 --out out/bench/cornell-classics
	$(BENCH) --anim orbit --frames 0:100 --size 320x240 --methods iir,ir --sweep bounces=2,4,8 \
	    --ref-spp 512 --ref-every 25 --out out/bench/cornell-bounces
	$(BENCH) --anim orbit --frames 0:100 --size 320x240 --methods iir,ir \
	    --sweep clamp_compensation=off,full,interleaved --ref-spp 1024 --ref-every 25 \
	    --out out/bench/cornell-compensation
	$(BENCH) --anim orbit --frames 0:100 --size 320x240 --methods iir \
	    --sweep target_fps=0,30,60,120 --ref-spp 1024 --ref-every 25 --out out/bench/cornell-controller
	$(foreach p,grazing:4 void:4 sweep-fast:8,$(BENCH) --anim $(word 1,$(subst :, ,$(p))) \
	    --size 256x192 --methods iir --insert-ms $(word 2,$(subst :, ,$(p))) --kmax 0 --ref-spp 64 \
	    --ref-every 2 --out out/bench/cornell-$(word 1,$(subst :, ,$(p)))-budget &&) true
	$(BENCH) conference --anim orbit --size 320x240 --methods iir --insert-ms 10 --kmax 0 \
	    --sm-res 64 --ref-spp 256 --ref-every 100 --out out/bench/conference-orbit-budget
	$(BENCH) cornell_spheres --anim orbit --frames 0:100 --size 320x240 \
	    --methods whitted,hybrid,radiosity,pt --bounces 8 --sweep spp=4,16 --ref-spp 512 \
	    --ref-every 25 --save-images --out out/bench/cornell-spheres
	$(BENCH) cornell_spheres --anim orbit --frames 0:40 --size 320x240 --methods iir,ir \
	    --sweep bounces=2,4 --ref-spp 512 --ref-every 20 --out out/bench/glossy-spheres
	$(BENCH) material_room --anim orbit --frames 0:40 --size 320x240 --methods iir,ir \
	    --sweep bounces=2,4 --ref-spp 256 --ref-every 20 --out out/bench/glossy-room
	$(foreach p,orbit sweep-fast teleport occluder corner grazing void,$(BENCH) --anim $(p) \
	    --methods iir,ir --sweep refill=false,true --size 128x96 --ref-spp 64 --ref-every 10 \
	    --out out/bench/refill/cornell_box-$(p) &&) true
	$(foreach k,cornell_point:orbit cornell_gltf_spot:orbit cornell_area:orbit breakfast_room:day \
	    breakfast_room:lamp-shade conference:orbit conference_points:drift,$(BENCH) \
	    $(word 1,$(subst :, ,$(k))) --anim $(word 2,$(subst :, ,$(k))) --frames 0:60 --methods iir,ir \
	    --sweep refill=false,true --size 128x96 --ref-spp 64 --ref-every 10 \
	    --out out/bench/refill/$(subst :,-,$(k)) &&) true
	$(foreach p,orbit sweep-fast teleport occluder corner grazing void,$(BENCH) --anim $(p) \
	    --methods iir,ir --size 128x96 --ref-spp 1024 --ref-every 10 \
	    --out out/bench/quiet-ref/cornell_box-$(p) &&) true
	$(foreach k,cornell_point:orbit cornell_gltf_spot:orbit cornell_area:orbit breakfast_room:day \
	    breakfast_room:lamp-shade conference:orbit,$(BENCH) $(word 1,$(subst :, ,$(k))) \
	    --anim $(word 2,$(subst :, ,$(k))) --frames 0:60 --methods iir,ir --size 128x96 \
	    --ref-spp 1024 --ref-every 10 --out out/bench/quiet-ref/$(subst :,-,$(k)) &&) true
	$(BENCH) conference --anim orbit --frames 0:60 --methods iir --size 128x96 --ref-spp 1024 \
	    --ref-every 10 --sweep weights=voronoi,surface --out out/bench/quiet-ref/conference-weights
	$(foreach spp,64 2048,$(BENCH) conference_points --anim drift --frames 0:22 --size 128x96 \
	    --methods iir,ir --ref-spp $(spp) --ref-every 10 \
	    --out out/bench/flicker-ref/conference_points-drift-$(spp) &&) true
	$(foreach s,cornell_spheres material_room,$(BENCH) $(s) --anim orbit --frames 10:14 \
	    --size 160x120 --methods iir,ir --sweep bounces=2,4 --ref-spp 4096 --ref-every 2 \
	    --out out/bench/glossy-flicker/$(s) &&) true
	$(BENCH) material_room --frames 0:4 --size 256x192 --methods iir,ir --sweep vpl_kind=point,sphere \
	    --sweep clamp=0,100 --ref-spp 512 --ref-every 2 --out out/bench/glossy-vsl
	$(foreach s,cornell_box conference,$(foreach z,512x384 1024x768,$(BENCH) $(s) --anim orbit \
	    --frames 0:60 --size $(z) --methods iir,ir --sweep shading=full,multires --ref-spp 0 \
	    --out out/bench/shading/$(s)-$(z) &&)) true
	$(foreach i,scalar sse2 avx2,IIR_ISA=$(i) $(BENCH) --anim orbit --frames 0:60 --size 512x384 \
	    --methods iir,ir --ref-spp 0 --out out/bench/shading/isa-$(i) &&) true
	$(foreach s,cornell_box conference,$(foreach i,scalar avx2,IIR_ISA=$(i) $(BENCH) $(s) --anim orbit \
	    --frames 0:60 --size 256x192 --methods iir,ir --ref-spp 256 --ref-every 10 \
	    --out out/bench/shading/images-$(s)-$(i) &&)) true
	rm -rf out/bench/ffcache && $(foreach a,0.008 0.002 0.0005,$(foreach run,compute load, \
	    IIR_CACHE_DIR=out/bench/ffcache $(BUILD)/iird render --method radiosity --patch-area $(a) \
	    --size 64x48 --out out/bench/ffcache/still.png 2>&1 | grep "form factors of" &&)) true
	/usr/bin/python3 tools/live_bench.py --iird $(BUILD)/iird --out out/bench/live.json

# Coverage-guided fuzzing of the daemon's input parsers (tests/fuzz/, issue 15): a clang build with
# libFuzzer, ASan and UBSan in $(FUZZ_BUILD), then each target for FUZZ_SECONDS from its seed corpus
# tests/fuzz/TARGET/. New corpus entries go to $(FUZZ_BUILD)/corpus/TARGET (scratch, not in git: copy
# the interesting ones into tests/fuzz/TARGET/, where `make test` replays them), crashes, leaks and
# timeouts to out/fuzz/TARGET-*. Fails when any target found something.
FUZZ_BUILD   ?= build-fuzz
FUZZ_SECONDS ?= 600
FUZZ_TARGETS ?= protocol anim sidecar scene pfm ffcache
FUZZ_DICT     = protocol anim sidecar
fuzz: deps
	CC=clang CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIIR_WERROR=ON \
	    -DIIR_SANITIZE=address,undefined -DIIR_FUZZ=ON >/dev/null
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target $(addprefix fuzz_,$(FUZZ_TARGETS))
	@mkdir -p out/fuzz $(FUZZ_BUILD)/test-tmp; status=0; \
	for t in $(FUZZ_TARGETS); do \
	    mkdir -p $(FUZZ_BUILD)/corpus/$$t; \
	    dict=; case " $(FUZZ_DICT) " in *" $$t "*) dict=-dict=tests/fuzz/protocol.dict;; esac; \
	    echo "== fuzz_$$t for $(FUZZ_SECONDS) s"; \
	    IIR_TEST_TMP=$(FUZZ_BUILD)/test-tmp OMP_NUM_THREADS=1 \
	        LSAN_OPTIONS=suppressions=$(CURDIR)/tests/fuzz/lsan.supp $(FUZZ_BUILD)/fuzz_$$t \
	        $(FUZZ_BUILD)/corpus/$$t tests/fuzz/$$t $$dict -max_total_time=$(FUZZ_SECONDS) \
	        -timeout=10 -rss_limit_mb=2048 -max_len=65536 -print_final_stats=1 \
	        -artifact_prefix=out/fuzz/$$t- || status=1; \
	done; exit $$status

# A soak of `iird serve` on loopback (tools/soak.py, issue #15): 32 clients dragging the light at 30 Hz
# for 60 s, then 1000 connect/close and 1000 hello-then-vanish cycles, watching /healthz, RSS, threads
# and fds; prints every pass criterion with its figure and fails when one does. ~3 min.
soak: build
	mkdir -p out
	/usr/bin/python3 tools/soak.py --iird $(BUILD)/iird --clients 32 --seconds 60 --cycles 1000 --out out/soak.json

# docs/cli.md's parameter tables, regenerated from the methods' own tables (a test compares them).
docs: build
	/usr/bin/python3 tools/gen_params_doc.py $(BUILD)/iird docs/cli.md

FORMAT_FILES = $(shell git ls-files '*.c' '*.h' '*.cpp' '*.hpp' 2>/dev/null)
format:
	clang-format -i $(FORMAT_FILES)
format-check:
	@clang-format --dry-run --Werror $(FORMAT_FILES) && echo "clang-format: clean"

clean:
	rm -rf $(BUILD) $(TEST_BUILD)
