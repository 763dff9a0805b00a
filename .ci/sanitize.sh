#!/usr/bin/env bash
# The sanitizer and fuzzing job of CI (called by .ci/run after the main test suite).
#
# One clang build with -DSIMREEL_FUZZ=ON: every target is compiled with AddressSanitizer,
# UndefinedBehaviorSanitizer and -fsanitize=float-cast-overflow (any report aborts), plus
# libFuzzer's coverage instrumentation. In that tree it
#   1. runs the sim unit tests and the scene-loader/CLI unit tests under the sanitizers,
#   2. replays the seed corpus (tests/fuzz/corpus, the demo scenes) through the fuzz target,
#   3. fuzzes the scene loader for a fixed number of inputs from a fixed seed (repeatable; 200,000 inputs
#      in about 30 s here), with the key dictionary, on a scratch copy of the corpus.
# The render, golden and determinism suites are left to the Release build: under ASan on two
# cores they would take most of an hour and exercise Mesa more than simreel.
#
# Environment: SANITIZE_BUILD_DIR (default build-sanitize), FUZZ_RUNS (default 200000),
# FUZZ_SECONDS (a hard stop for step 3, default 300). A longer campaign: see README "Fuzzing".
set -euo pipefail
cd "$(dirname "$0")/.."

dir=${SANITIZE_BUILD_DIR:-build-sanitize}
runs=${FUZZ_RUNS:-200000}
seconds=${FUZZ_SECONDS:-300}

t0=$(date +%s)
CXX=clang++ cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSIMREEL_FUZZ=ON \
  -DSIMREEL_BUILD_BENCH=OFF >/dev/null
cmake --build "$dir" -j2 --target test_sim test_demos simreel fuzz_scene fuzz_scene_replay
t1=$(date +%s)
echo "sanitize: build took $((t1 - t0)) s"

# Leak checking stays on for simreel's code; Mesa's llvmpipe keeps driver-lifetime allocations
# that LeakSanitizer would report from the CLI tests that render, so those are suppressed by
# library name only.
supp=$(mktemp)
trap 'rm -f "$supp"' EXIT
printf 'leak:libLLVM\nleak:libgallium\nleak:swrast_dri\nleak:libOSMesa\nleak:libglapi\nleak:libEGL_mesa\n' >"$supp"
export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1:strict_string_checks=1
export LSAN_OPTIONS=suppressions=$supp:print_suppressions=0
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

# Under ASan/UBSan the physics runs ~30x slower: test_sim and test_demos took 26 min on the
# 2-core machine, and the whole of .ci/run 72 min of CI's 90. These long-horizon tests repeat
# code paths shorter tests run too (a 210-box pyramid for 10 s beside the 10-box stack; a cloth
# folding onto itself beside the two-cloth drop; a ball caught by a pinned sheet, 226 s here,
# beside the kinematic sphere through a sheet and the cloth on a light box; a 20-link chain for
# 60 s beside the shorter chains); they all run in the Release suite. OpenMP's spinning wait
# makes the 2- and 4-thread determinism tests crawl on 2 cores. Without the first three and with
# the passive wait test_sim took 15 min. The whole cloth_pile demo (SceneBodies, 120 frames of a
# sheet on eight bodies: 12.6 s in Release) added 400 s here; BodyCoupling's cloth tests run the
# same coupling code.
export OMP_WAIT_POLICY=passive
heavy='DynamicBodies.PyramidOfTwentyRowsStandsTenSeconds:Cloth.SelfCollisionFoldsNeverIntersect'
heavy+=':Joints.SwingingTwentyLinkChainDriftsLessThanATenthOfAMillimetreInSixtySeconds'
heavy+=':BodyCoupling.ABallIsCaughtByAPinnedSheetNeverThrough'
"$dir/tests/sim/test_sim" --gtest_brief=1 --gtest_filter="-$heavy"
"$dir/tests/demos/test_demos" --gtest_brief=1 --gtest_filter='-SceneBodies.ClothPileDemoKeepsEveryBodyCalm'
t2=$(date +%s)
echo "sanitize: unit tests took $((t2 - t1)) s"

"$dir/tests/fuzz/fuzz_scene_replay" tests/fuzz/corpus
scratch=$(mktemp -d)
trap 'rm -f "$supp"; rm -rf "$scratch"' EXIT
cp tests/fuzz/corpus/*.json "$scratch/"
mkdir -p "$dir/fuzz-artifacts"
"$dir/tests/fuzz/fuzz_scene" "$scratch" -dict=tests/fuzz/scene.dict -seed=1 -runs="$runs" \
  -max_total_time="$seconds" -max_len=16384 -timeout=10 -rss_limit_mb=2048 \
  -artifact_prefix="$dir/fuzz-artifacts/" -print_final_stats=1
t3=$(date +%s)
echo "sanitize: corpus replay and $runs fuzz inputs took $((t3 - t2)) s"
