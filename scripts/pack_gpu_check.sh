#!/usr/bin/env bash
# Packs what scripts/gpu_check.sh runs on a lent GPU machine, where nothing is compiled (docs/gpu-check.md):
# a Release build of the test suites, the benches, the gust CLI and the sample game, made here in build-gpu/,
# and every shared library they and the Khronos validation layer load except glibc's, as one archive,
# .gpucheck/gpucheck.tar.xz. Also fetches the Vulkan loader's packages into .gl/ when they are missing (the
# device tool's README). Both folders are ignored by git and travel with `carry`.
#
# The working tree that travels to the lent machine may hold 64 MiB, the repository itself included, so
# the script fails when the archive and .gl/ leave less than 2 MiB of that.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build-gpu"
pack="$root/.gpucheck"
limit_mib=64

# The binaries gpu_check.sh runs, relative to the build folder. gust_scene_tests is left out: it reads
# assimp's test models from /usr/share/assimp/models, which a GPU machine lacks, and touches no GPU.
binaries=(
    tests/gpu/gust_gpu_tests
    tests/voxelizer/gust_voxelizer_tests
    tests/solver/gust_solver_tests
    tests/plugin/gust_plugin_tests
    tests/plugin/gust_host_memory_tests
    tests/plugin/gust_c_api_test
    tests/physics/gust_physics_tests
    tests/scene/gust_scene_link_order_tests
    tests/cli/gust_cli_tests
    tests/docs/gust_docs_tests
    tests/sample/gust_sample_tests
    tests/sample/gust_sample_core_tests
    bench/gust_bench_solver
    bench/gust_bench_voxelize
    bench/gust_bench_tree
    bench/gust_bench_cascades
    cli/gust
    sample_game/gust_sample
)
# glibc and the dynamic loader, which every Linux has and which must match each other; libvulkan comes
# from .gl/ (the loader the device tool's README brings); linux-vdso is the kernel's.
base_system='^(linux-vdso\.so|ld-linux-x86-64\.so|libc\.so|libm\.so|libdl\.so|libpthread\.so|librt\.so|libutil\.so|libresolv\.so|libvulkan\.so)'
# Kept apart and used only where the machine has none: a machine's own newer libstdc++ serves our
# binaries too, and its driver may need the newer one.
fallback='^(libstdc\+\+\.so|libgcc_s\.so)'
layer_json=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json

# Paths relative to the checkout's parent, so checkouts side by side share ccache's entries.
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
launcher=()
if command -v ccache >/dev/null; then
    launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DGUST_WARNINGS_AS_ERRORS=ON \
    -DGUST_BUILD_TESTS=ON -DGUST_BUILD_BENCH=ON -DGUST_BUILD_SAMPLE=ON -DGUST_WITH_OPENVDB=ON "${launcher[@]}" \
    >/dev/null
targets=()
for b in "${binaries[@]}"; do targets+=("$(basename "$b")"); done
nice cmake --build "$build" --parallel "$(nproc)" --target "${targets[@]}"

stage="$(mktemp -d)"
trap 'rm -rf "$stage"' EXIT
mkdir -p "$stage/build" "$stage/lib" "$stage/lib-fallback" "$stage/layer"
for b in "${binaries[@]}"; do
    mkdir -p "$stage/build/$(dirname "$b")"
    strip --strip-unneeded -o "$stage/build/$b" "$build/$b"
done

layer_so="$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["layer"]["library_path"])' \
    "$layer_json")"
[[ "$layer_so" == /* ]] || layer_so="/usr/lib/x86_64-linux-gnu/$layer_so"
cp "$layer_so" "$stage/layer/"
# A relative library_path is relative to the manifest.
python3 - "$layer_json" "$stage/layer/VkLayer_khronos_validation.json" "$(basename "$layer_so")" <<'EOF'
import json, sys
manifest = json.load(open(sys.argv[1]))
manifest["layer"]["library_path"] = "./" + sys.argv[3]
json.dump(manifest, open(sys.argv[2], "w"), indent=4)
EOF

# Every library the binaries and the layer need, found by ldd here, copied unless the base system has it.
for f in "$stage"/build/*/* "$stage"/build/*/*/* "$stage/layer/$(basename "$layer_so")"; do
    [[ -f "$f" ]] && ldd "$f"
done | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' | sort -u | while read -r name path; do
    if [[ "$name" =~ $base_system ]]; then continue; fi
    if [[ "$name" =~ $fallback ]]; then dest="$stage/lib-fallback"; else dest="$stage/lib"; fi
    cp -L "$path" "$dest/$name"
done

{
    echo "source_dir=$root"
    echo "build_dir=$build"
    echo "commit=$(git -C "$root" rev-parse HEAD)$(git -C "$root" diff --quiet HEAD -- . ':!docs' || echo '+changes')"
    echo "packed=$(date -u '+%Y-%m-%d %H:%M UTC')"
    echo "packed_on=$(. /etc/os-release && echo "$PRETTY_NAME")"
} >"$stage/MANIFEST"

rm -rf "$pack"
mkdir -p "$pack"
tar -C "$stage" -cf - . | xz -T0 -9 >"$pack/gpucheck.tar.xz"
cp "$stage/MANIFEST" "$pack/MANIFEST"

if ! ls "$root"/.gl/*.deb >/dev/null 2>&1; then
    lists="$(mktemp -d)"
    mkdir -p "$root/.gl" "$lists/partial"
    o=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists="$lists")
    apt-get "${o[@]}" update >/dev/null
    (cd "$root/.gl" && apt-get "${o[@]}" download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
fi

mib() { du -sb "$@" | awk '{s += $1} END {printf "%.1f", s / 1048576}'; }
tracked="$(git -C "$root" ls-files -z | (cd "$root" && xargs -0 stat -c %s) | awk '{s += $1} END {printf "%.1f", s / 1048576}')"
unpacked="$(mib "$stage")"
archive="$(mib "$pack/gpucheck.tar.xz")"
gl="$(mib "$root/.gl")"
total="$(awk -v a="$tracked" -v b="$archive" -v c="$gl" 'BEGIN {printf "%.1f", a + b + c}')"
libs=("$stage"/lib/*.so* "$stage"/lib-fallback/*.so*)
echo "packed ${#libs[@]} libraries and ${#binaries[@]} binaries:" \
    "$unpacked MiB unpacked, $archive MiB as .gpucheck/gpucheck.tar.xz; .gl/ $gl MiB;" \
    "with the repository's tracked files ($tracked MiB) $total of the $limit_mib MiB that may travel"
if awk -v t="$total" -v l="$limit_mib" 'BEGIN {exit !(t > l - 2)}'; then
    echo "pack_gpu_check.sh: the working tree would not travel (over $((limit_mib - 2)) MiB)" >&2
    exit 1
fi
