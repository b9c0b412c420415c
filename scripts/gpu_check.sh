#!/usr/bin/env bash
# The GPU check (docs/gpu-check.md): runs on a lent GPU machine, from the repository's root, what
# scripts/pack_gpu_check.sh packed here, compiling nothing: the test suites with the validation layer, the
# solver bench (32x16x32, 64^3 and 128^3, to 1e-3 and at 2 V-cycles a frame), the voxelize bench (the
# instanced dragon at 512^3), the tree bench, the cascades bench (finest grid 64x32x64 cells of 0.5 m, up to
# 4 cascades of ratio 4) and the sample game headless at --quality high for 300 frames.
# The benches write their blocks into a copy of docs/results.md (`-gpu` blocks on a GPU). Everything goes
# to $OUT (default out/gpu-check): results.md, gpu_check.log, tests.log, sample.log and summary.txt.
#
# Each step has a timeout, and all of them together end within GPU_CHECK_SECONDS (default 470), so one
# hang cannot eat the machine's time. GPU_CHECK_SMALL=1 runs the same steps at small sizes and a few frames,
# the rehearsal on lavapipe.
set -uo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root" || exit 1
out="${OUT:-$root/out/gpu-check}"
small="${GPU_CHECK_SMALL:-0}"
# Timeouts are multiplied by the scale: lavapipe, which the rehearsal runs on, is slower than any GPU.
scale="${GPU_CHECK_SCALE:-$([[ "$small" == 1 ]] && echo 8 || echo 1)}"
budget="${GPU_CHECK_SECONDS:-$((470 * scale))}"
work="${GPU_CHECK_WORK:-/tmp/gust-gpu-check}"
start=$(date +%s)
mkdir -p "$out"
log="$out/gpu_check.log"
summary="$out/summary.txt"
: >"$log"
: >"$summary"

say() { echo "gpu_check: $*" | tee -a "$log" >&2; }
left() { echo $((budget - ($(date +%s) - start))); }

# Runs a step under a timeout of at most `cap` seconds, fewer when the budget is short (keeping `reserve`
# seconds for the steps after it); its output goes to the log (and to `file`, when given).
# step NAME CAP RESERVE FILE COMMAND...
step() {
    local name="$1" cap="$2" reserve="$3" file="$4"
    shift 4
    local limit
    cap=$((cap * scale))
    limit=$(($(left) - reserve * scale))
    ((limit > cap)) && limit=$cap
    if ((limit < 10)); then
        say "$name: skipped, $(left) s left"
        echo "$name: skipped (out of time)" >>"$summary"
        return
    fi
    say "$name: $* (timeout ${limit} s)"
    local t0 rc
    t0=$(date +%s)
    if [[ -n "$file" ]]; then
        timeout -k 10 "$limit" "$@" >>"$file" 2>&1
        rc=$?
        tail -n 40 "$file" >>"$log"
    else
        timeout -k 10 "$limit" "$@" >>"$log" 2>&1
        rc=$?
    fi
    local verdict="ok"
    ((rc == 124 || rc == 137)) && verdict="timed out"
    ((rc != 0 && rc != 124 && rc != 137)) && verdict="failed (exit $rc)"
    say "$name: $verdict after $(($(date +%s) - t0)) s"
    echo "$name: $verdict, $(($(date +%s) - t0)) s" >>"$summary"
}

# The Vulkan loader: from the .gl packages (unpacked into /, as the device tool's README says) where the
# machine has none.
if ! ldconfig -p | grep -q 'libvulkan\.so\.1 '; then
    if ls .gl/*.deb >/dev/null 2>&1; then
        say "no Vulkan loader: unpacking .gl/*.deb into /"
        for f in .gl/*.deb; do dpkg -x "$f" /; done
        ldconfig
    else
        say "no Vulkan loader and no .gl/ packages: carry .gl (docs/gpu-check.md)"
    fi
fi
# The NVIDIA driver's ICD where the loader would not find it.
nvidia_icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if [[ -f "$nvidia_icd" ]] && ! ls /usr/share/vulkan/icd.d/nvidia* /etc/vulkan/icd.d/nvidia* >/dev/null 2>&1; then
    export VK_DRIVER_FILES="$nvidia_icd"
    export __EGL_VENDOR_LIBRARY_FILENAMES=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
fi

say "unpacking .gpucheck/gpucheck.tar.xz into $work"
rm -rf "$work"
mkdir -p "$work"
if command -v xz >/dev/null; then
    tar -C "$work" -xJf .gpucheck/gpucheck.tar.xz
else
    python3 -c 'import sys, tarfile; tarfile.open(sys.argv[1]).extractall(sys.argv[2])' \
        .gpucheck/gpucheck.tar.xz "$work"
fi || {
    say "cannot unpack .gpucheck/gpucheck.tar.xz: run scripts/pack_gpu_check.sh and carry .gpucheck"
    exit 1
}
cat "$work/MANIFEST" >>"$summary"

# The binaries hold the paths they were built at (assets, test data, the sources the docs tests read, the
# CLI and the sample the tests start): make those paths lead here.
source_dir="$(sed -n 's/^source_dir=//p' "$work/MANIFEST")"
build_dir="$(sed -n 's/^build_dir=//p' "$work/MANIFEST")"
if [[ "$source_dir" != "$root" ]]; then
    if [[ -e "$source_dir" ]]; then
        say "$source_dir exists here: the binaries read their assets and data from it, not from $root"
    else
        mkdir -p "$(dirname "$source_dir")"
        ln -s "$root" "$source_dir"
    fi
fi
if [[ ! -e "$build_dir" || -L "$build_dir" ]]; then
    rm -f "$build_dir"
    ln -s "$work/build" "$build_dir"
elif [[ "$(readlink -f "$build_dir")" != "$(readlink -f "$work/build")" ]]; then
    say "$build_dir exists here: the tests start the CLI and the sample from it, not from the pack"
fi

export LD_LIBRARY_PATH="$work/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
if ! ldconfig -p | grep -q 'libstdc++\.so\.6 '; then
    export LD_LIBRARY_PATH="$LD_LIBRARY_PATH:$work/lib-fallback"
fi
export VK_LAYER_PATH="$work/layer"
bin="$work/build"
missing="$(for f in "$bin"/*/* "$bin"/*/*/*; do [[ -f "$f" ]] && ldd "$f" | grep 'not found'; done | sort -u)"
if [[ -n "$missing" ]]; then
    say "libraries not found: $missing"
fi
{
    echo "machine: $(uname -m), $(. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME"), $(nproc) cores"
    command -v nvidia-smi >/dev/null && nvidia-smi -L
    echo "libraries not found: ${missing:-none}"
} >>"$summary"

# The benches run in the pack's folder as build/bench/..., writing docs/results.md there, which is $OUT's
# copy: their blocks' Command lines then read as those run here do.
cp docs/results.md "$out/results.md"
ln -sfn "$out" "$work/docs"

# The test suites, four binaries at a time, each under its own timeout; their output in tests.log.
tests_log="$out/tests.log"
: >"$tests_log"
run_tests() {
    local per_binary="$1" dir
    dir="$(mktemp -d)"
    local tests=(gpu/gust_gpu_tests voxelizer/gust_voxelizer_tests solver/gust_solver_tests
        plugin/gust_plugin_tests plugin/gust_host_memory_tests plugin/gust_c_api_test
        physics/gust_physics_tests scene/gust_scene_link_order_tests cli/gust_cli_tests docs/gust_docs_tests
        sample/gust_sample_tests sample/gust_sample_core_tests)
    # The rehearsal (GPU_CHECK_SMALL=1) runs the first two tests of each suite: lavapipe takes minutes for
    # the whole suite.
    printf '%s\n' "${tests[@]}" | xargs -P 4 -I{} sh -c \
        'name=$(basename "$5"); cd "$3" || exit 1; filter="*";
         if [ "$6" = 1 ] && [ "$name" != gust_c_api_test ]; then
             filter=$("$1/tests/$5" --gtest_list_tests | awk "/^[^ ]/ {s = \$1} /^  / {print s \$1}" | head -n 2 |
                 paste -sd:);
         fi;
         if [ "$name" = gust_sample_tests ] && [ -n "$7" ]; then filter="$filter-$7"; fi;
         timeout -k 5 "$2" "$1/tests/$5" --gtest_brief=1 --gtest_filter="$filter" >"$4/$name.log" 2>&1;
         echo "$name: exit $?" >>"$4/verdicts"' _ "$bin" "$per_binary" "$root" "$dir" {} "$small" "$sample_skip"
    local failed=0 t
    for t in "${tests[@]}"; do
        t="$(basename "$t")"
        echo "==== $t" && cat "$dir/$t.log"
    done
    echo "==== verdicts"
    sort "$dir/verdicts"
    grep -qv ': exit 0$' "$dir/verdicts" && failed=1
    rm -rf "$dir"
    return $failed
}
export -f run_tests
# The sample's tests that start Xvfb or encode the tour's WebP need tools a lent machine may lack (it
# reaches no package mirror): those are left out there, and the summary says which.
sample_skip=""
command -v xvfb-run >/dev/null || sample_skip="*Xvfb*:*AtTheWindow*"
command -v img2webp >/dev/null || sample_skip="${sample_skip:+$sample_skip:}*Webp:*VideoOfOnePass"
[[ -n "$sample_skip" ]] && echo "sample tests left out (xvfb-run or img2webp missing): $sample_skip" >>"$summary"
export bin root small sample_skip

if [[ "$small" == 1 ]]; then
    solver_args=(--sizes 16 --repeat 1 --solve-max-cells 1 --frame-cycles 2 --tolerance 1e-3 --budget 5)
    voxelize_args=(--quick --res "32,64" --repeat 1)
    tree_args=(--quick --repeat 1 --frames 2)
    cascades_args=(--frames 8)
    sample_args=(--quality low --frames 3 --cells "16,8,16")
else
    solver_args=(--sizes 32x16x32 64 128 --repeat 5 --budget 20 --solve-max-cells 2097152 --frame-cycles 2
        --tolerance 1e-3)
    voxelize_args=(--res 512 --repeat 3)
    tree_args=(--repeat 5)
    cascades_args=(--cells 64,32,64 --cell-size 0.5)
    sample_args=(--quality high --frames 300)
fi

# Caps: 160 + 100 + 60 + 50 + 40 + 60 s; each step keeps the later ones' caps in reserve.
step tests 160 310 "$tests_log" bash -c "run_tests $((150 * scale))"
step solver 100 210 "" env -C "$work" build/bench/gust_bench_solver "${solver_args[@]}" --write docs/results.md
step voxelize 60 150 "" env -C "$work" build/bench/gust_bench_voxelize "${voxelize_args[@]}" --write docs/results.md
step tree 50 100 "" env -C "$work" build/bench/gust_bench_tree "${tree_args[@]}" --write docs/results.md
step cascades 40 60 "" env -C "$work" build/bench/gust_bench_cascades "${cascades_args[@]}" --write docs/results.md
rm -rf "$work/sample"
step sample 60 0 "$out/sample.log" "$bin/sample_game/gust_sample" --headless --no-video --png-every 100000 \
    --out "$work/sample" "${sample_args[@]}"

say "done in $(($(date +%s) - start)) s; $out: $(ls "$out" | tr '\n' ' ')"
echo "total: $(($(date +%s) - start)) s" >>"$summary"
cat "$summary" >&2
! grep -q 'failed\|timed out' "$summary"
