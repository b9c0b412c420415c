// The results block of gust_bench_tree: build time against depth beside the seed's, bytes per
// representation, and the walk-through's incremental frames against rebuilds.
#include "tree_bench.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <sstream>

namespace gust::bench::tree {

double median(std::vector<double> values) {
    if (values.empty()) return 0.0;
    std::sort(values.begin(), values.end());
    const std::size_t mid = values.size() / 2;
    return values.size() % 2 ? values[mid] : 0.5 * (values[mid - 1] + values[mid]);
}

namespace {

/// Formats one of the seed's times with the three decimals it was reported with.
std::string fmt_seed(double ms) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.3f", ms);
    return text;
}

/// The first section: build time against depth, b = 2 beside the seed's column.
void render_depth(std::ostringstream& out, const std::vector<TreeRow>& rows, const Voxelized& fragments,
                  std::uint64_t triangles, const Plan& plan, std::vector<std::string>& notes) {
    const bool seed_grid = plan.depth_res == 512;
    out << "### Tree build time against depth at " << plan.depth_res << "^3 (seed table 2)\n\n";
    out << "One compute-path voxelization of `scans/dragon_full.glb` (" << grouped(triangles)
        << " triangles, one instance, `grid_around` its bounds at " << plan.depth_res << "^3, "
        << fmt_ms(fragments.wall_ms) << " ms) gives " << grouped(fragments.fragments) << " fragments ("
        << grouped(fragments.unique.size())
        << " unique voxels), and every row builds its tree from scratch over that same list: a depth-d "
           "tree of branching b has b^d voxels per axis and takes the fragment keys shifted right by the "
           "stated amount, so its leaves cover 2^shift fragment voxels per axis, as the seed's depth "
           "parameter does. Wall ms is around one blocking `SparseTree::update(&fragments, nullptr)`, best "
           "of the stated runs after an untimed build that also grew the pools until nothing was refused; "
           "the runs go in rounds over all rows, so that a change in load falls on every row alike; "
           "GPU ms sums that build's timestamp passes (`tree_begin`, `tree_static`, `tree_coarsen`). Nodes "
           "counts the root and every node of the interior levels; leaf bricks are the b^3-bit masks of the "
           "last level. \"= host\" compares the tree's leaf voxels with the host's count of unique fragment "
           "voxels at the tree's resolution.";
    if (seed_grid)
        out << " The seed column is the seed report's RTX 2070 Super time for its " << grouped(kSeedTriangles)
            << "-triangle XYZRGB dragon at the same depth.";
    out << "\n\n| Branching | Depth | Tree grid | Shift | Runs | Wall ms | GPU ms | Nodes | Leaf bricks "
           "| Leaf voxels | = host | Pool growths | Seed ms |\n";
    out << "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|--:|--:|\n";
    for (const TreeRow& row : rows) {
        const bool seed = seed_grid && row.branching == 2 && row.depth <= std::size(kSeedDepthMs);
        out << "| " << row.branching << " | " << row.depth << " | " << row.res() << "^3 | " << row.shift
            << " | " << row.runs << " | ";
        if (!row.ok()) {
            out << failed_cell(
                       notes, "b = " + std::to_string(row.branching) + ", depth " + std::to_string(row.depth),
                       row.error)
                << " | | | | | | | ";
        } else {
            out << fmt_ms(row.wall_ms) << " | "
                << (row.gpu_ms < 0.0 ? std::string("n/a") : fmt_ms(row.gpu_ms)) << " | "
                << grouped(row.stats.nodes) << " | " << grouped(row.leaf_bricks()) << " | "
                << grouped(row.stats.voxels) << " | "
                << (row.stats.voxels == row.host_voxels ? std::string("yes")
                                                        : "no (host " + grouped(row.host_voxels) + ")")
                << " | " << row.growths << " | ";
        }
        out << (seed ? fmt_seed(kSeedDepthMs[row.depth - 1]) : std::string("-")) << " |\n";
    }

    std::vector<const TreeRow*> octree;
    for (const TreeRow& row : rows)
        if (row.branching == 2 && row.ok()) octree.push_back(&row);
    if (octree.size() >= 2) {
        const TreeRow& first = *octree.front();
        const TreeRow& last = *octree.back();
        out << "\nFor b = 2, the build took " << fmt_ms(first.wall_ms) << " ms wall (" << fmt_ms(first.gpu_ms)
            << " ms GPU) at depth " << first.depth << " and " << fmt_ms(last.wall_ms) << " ms wall ("
            << fmt_ms(last.gpu_ms) << " ms GPU) at depth " << last.depth << ", "
            << fmt_ratio(last.gpu_ms / first.gpu_ms) << " in GPU time";
        if (seed_grid && last.depth <= std::size(kSeedDepthMs))
            out << "; the seed's went from " << fmt_seed(kSeedDepthMs[first.depth - 1]) << " to "
                << fmt_seed(kSeedDepthMs[last.depth - 1]) << " ms over the same depths ("
                << fmt_ratio(kSeedDepthMs[last.depth - 1] / kSeedDepthMs[first.depth - 1])
                << "). The seed's depth 10 (" << fmt_seed(kSeedDepthMs[9])
                << " ms) needs 1024^3 fragments and has no row here; the bytes table below builds that tree";
        out << ".";
    }
    const TreeRow* fastest = nullptr;
    for (const TreeRow& row : rows)
        if (row.ok() && row.shift == 0 && (!fastest || row.gpu_ms < fastest->gpu_ms)) fastest = &row;
    if (fastest) {
        out << " Among the trees whose leaves are the fragment voxels (shift 0), b = " << fastest->branching
            << " built fastest (" << fmt_ms(fastest->gpu_ms) << " ms GPU)";
        for (const TreeRow& row : rows)
            if (row.ok() && row.shift == 0 && &row != fastest)
                out << "; b = " << row.branching << " took " << fmt_ratio(row.gpu_ms / fastest->gpu_ms)
                    << " as long";
        out << ".";
    }
    bool all_match = true;
    for (const TreeRow& row : rows)
        if (row.ok() && row.stats.voxels != row.host_voxels) all_match = false;
    out << (all_match ? " Every tree's leaf voxel count equals the host's count."
                      : " Some trees' leaf voxel counts differ from the host's count (see \"= host\").")
        << "\n\n";
}

/// The second section: bytes of each representation, and of the trees beside the fragment list.
void render_bytes(std::ostringstream& out, const std::vector<Voxelized>& grids,
                  const std::vector<TreeRow>& trees, const Plan& plan, std::vector<std::string>& notes) {
    out << "### Bytes per representation (seed table 3)\n\n";
    out << "The same dragon, voxelized separately at each grid (compute path, `grid_around` its bounds). "
           "The dense grid is counted at 4 bytes per voxel (as the seed counted its regular grid) and at "
           "1 bit per voxel; the fragment list at 4 bytes per entry, and with the 8-byte velocities the "
           "voxelizer keeps for dynamic fragments; the unique voxels at 4 bytes per key. Tree bytes are "
           "`TreeStats::pool_bytes`: live node blocks (b^3 nodes of 8 bytes: child index and last-touched "
           "frame) and live leaf mask blocks (static and dynamic b^3-bit masks plus a frame word), not the "
           "pools' spare capacity, which is shown separately. Each tree's leaves are the grid's voxels "
           "(shift 0). The goal is tree bytes at most "
        << fmt_ratio(kBytesGoal) << " the fragment list's; the seed's octree took "
        << fmt_ratio(double(kSeedTreeBytes) / double(kSeedFragmentBytes)) << ".\n\n";
    out << "| Grid | Dense grid B | Bit grid B | Fragments | Fragment list B | With velocities B | "
           "Unique voxels | Unique voxel list B | Fragments per voxel |\n";
    out << "|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    for (const Voxelized& g : grids) {
        if (std::find(plan.byte_res.begin(), plan.byte_res.end(), g.res) == plan.byte_res.end()) continue;
        const std::uint64_t cells = std::uint64_t(g.res) * g.res * g.res;
        out << "| " << g.res << "^3 | " << grouped(cells * 4) << " | " << grouped(cells / 8) << " | "
            << grouped(g.fragments) << " | " << grouped(g.fragments * 4) << " | "
            << grouped(g.fragments * (4 + kVelocityBytes)) << " | " << grouped(g.unique.size()) << " | "
            << grouped(g.unique.size() * 4) << " | "
            << fmt_ratio(double(g.fragments) / double(std::max<std::size_t>(g.unique.size(), 1))) << " |\n";
    }
    out << "| 512^3 (seed) | " << grouped(kSeedGridBytes) << " | - | " << grouped(kSeedFragmentBytes / 4)
        << " | " << grouped(kSeedFragmentBytes) << " | - | - | - | - |\n\n";

    out << "| Grid | Branching | Depth | Nodes | Leaf bricks | Tree pool B | Pool capacity B | "
           "Tree / fragment list | Tree / unique voxel list | Tree / bit grid | Meets "
        << fmt_ratio(kBytesGoal) << " |\n";
    out << "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|---|\n";
    std::vector<std::string> met, missed;
    for (const TreeRow& row : trees) {
        const auto g =
            std::find_if(grids.begin(), grids.end(), [&](const Voxelized& v) { return v.res == row.res(); });
        const std::string where =
            "b = " + std::to_string(row.branching) + " at " + std::to_string(row.res()) + "^3";
        out << "| " << row.res() << "^3 | " << row.branching << " | " << row.depth << " | ";
        if (!row.ok() || g == grids.end()) {
            out << failed_cell(notes, where, row.ok() ? "no fragment list" : row.error)
                << " | | | | | | | |\n";
            continue;
        }
        const double list_ratio = double(row.stats.pool_bytes) / double(g->fragments * 4);
        const std::uint64_t cells = std::uint64_t(g->res) * g->res * g->res;
        const bool ok = list_ratio <= kBytesGoal;
        (ok ? met : missed).push_back(where + " (" + fmt_ratio(list_ratio) + ")");
        out << grouped(row.stats.nodes) << " | " << grouped(row.leaf_bricks()) << " | "
            << grouped(row.stats.pool_bytes) << " | " << grouped(row.stats.capacity_bytes) << " | "
            << fmt_ratio(list_ratio) << " | "
            << fmt_ratio(double(row.stats.pool_bytes) /
                         double(std::max<std::size_t>(g->unique.size(), 1) * 4))
            << " | " << fmt_ratio(double(row.stats.pool_bytes) / double(cells / 8)) << " | "
            << (ok ? "yes" : "no") << " |\n";
    }
    out << "| 512^3 (seed) | 2 | 9 | - | - | " << grouped(kSeedTreeBytes) << " | - | "
        << fmt_ratio(double(kSeedTreeBytes) / double(kSeedFragmentBytes)) << " | - | - | no |\n\n";
    const auto list = [](const std::vector<std::string>& items) {
        std::string text;
        for (std::size_t i = 0; i < items.size(); ++i)
            text += (i ? "; " : "") + items[i];
        return text.empty() ? std::string("none") : text;
    };
    out << "Trees within " << fmt_ratio(kBytesGoal) << " of the fragment list: " << list(met)
        << ". Trees above it: " << list(missed) << ".";
    std::vector<std::string> smaller;
    for (const TreeRow& row : trees) {
        const auto g =
            std::find_if(grids.begin(), grids.end(), [&](const Voxelized& v) { return v.res == row.res(); });
        if (row.ok() && g != grids.end() && row.stats.pool_bytes < g->unique.size() * 4)
            smaller.push_back("b = " + std::to_string(row.branching) + " at " + std::to_string(row.res()) +
                              "^3");
    }
    out << " The fragment list repeats a voxel once per triangle touching it (see fragments per voxel); "
           "trees smaller than a plain list of the unique voxels at 4 bytes each: "
        << list(smaller) << ".\n\n";
}

/// The third section: median incremental frame against median rebuild, and where the time goes.
void render_world(std::ostringstream& out, const WorldResult& world, const Plan& plan) {
    out << "### Incremental frame against rebuild (b = 4, " << world.grid.res << "^3)\n\n";
    out << "A static scene of " << grouped(world.static_triangles) << " triangles: " << world.scene
        << ". Grid " << world.grid.res << "^3 with h = " << world.grid.voxel_size << " m from ("
        << world.grid.origin.x << ", " << world.grid.origin.y << ", " << world.grid.origin.z
        << ") m, branching 4, compute-path voxelization, one `VoxelWorld`. Each frame poses the character on "
           "the CPU (`AnimatedMesh::pose`), uploads it (`VoxelWorld::update_positions`) and calls "
           "`VoxelWorld::step(character, 1/30 s)`; wall ms is around `step()` alone and GPU ms sums its "
           "timestamp passes. Incremental frames leave the static set unchanged, so a step voxelizes the "
           "character (with velocities) and updates the tree; they follow "
        << plan.warmup_frames << " untimed frames"
        << (std::uint32_t(plan.warmup_frames) > world.hysteresis
                ? ", more than the tree's hysteresis of " + std::to_string(world.hysteresis) +
                      " frames, so coarsening is in its steady state"
                : ", no more than the tree's hysteresis of " + std::to_string(world.hysteresis) +
                      " frames, so coarsening has not reached its steady state")
        << ". Rebuild frames rotate the order of the static instances before each step (the same "
           "geometry, but `set_static` sees a changed set), so the static set is voxelized again and the "
           "tree rebuilt from scratch as well; they follow "
        << plan.rebuild_warmup << " untimed rebuild frame(s).\n\n";
    out << "| Frame | Frames | Wall ms (median) | GPU ms (median) | Wall ms (min - max) | "
           "Static fragments | Dynamic fragments (median) | Blocks refined (total) | "
           "Blocks coarsened (total) | Tree nodes (last) | Leaf voxels (last) | Pool B (last) |\n";
    out << "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    const auto row = [&](const char* kind, const std::vector<FrameSample>& frames) {
        std::vector<double> wall, gpu, dyn;
        std::uint64_t refined = 0, coarsened = 0;
        for (const FrameSample& f : frames) {
            wall.push_back(f.wall_ms);
            gpu.push_back(f.gpu_ms);
            dyn.push_back(double(f.frame.dynamic_voxelize.fragments));
            refined += f.frame.tree.refined;
            coarsened += f.frame.tree.coarsened;
        }
        const FrameSample& last = frames.back();
        out << "| " << kind << " | " << frames.size() << " | " << fmt_ms(median(wall)) << " | "
            << fmt_ms(median(gpu)) << " | " << fmt_ms(*std::min_element(wall.begin(), wall.end())) << " - "
            << fmt_ms(*std::max_element(wall.begin(), wall.end())) << " | "
            << grouped(last.frame.static_voxelize.fragments) << " | " << grouped(std::uint64_t(median(dyn)))
            << " | " << grouped(refined) << " | " << grouped(coarsened) << " | "
            << grouped(last.frame.tree.nodes) << " | " << grouped(last.frame.tree.voxels) << " | "
            << grouped(last.frame.tree.pool_bytes) << " |\n";
    };
    row("incremental", world.incremental);
    row("rebuild", world.rebuild);

    std::map<std::string, std::pair<std::vector<double>, std::vector<double>>> passes;
    std::vector<std::string> order;
    const auto collect = [&](const std::vector<FrameSample>& frames, bool rebuild) {
        for (const FrameSample& f : frames)
            for (const auto& [pass, ms] : f.frame.ms) {
                const std::string name(pass);
                if (!passes.count(name)) order.push_back(name);
                (rebuild ? passes[name].second : passes[name].first).push_back(ms);
            }
    };
    collect(world.incremental, false);
    collect(world.rebuild, true);
    out << "\n| Pass | Incremental GPU ms (median) | Rebuild GPU ms (median) |\n|---|--:|--:|\n";
    for (const std::string& name : order) {
        const auto& [inc, reb] = passes.at(name);
        out << "| `" << name << "` | " << (inc.empty() ? std::string("-") : fmt_ms(median(inc))) << " | "
            << (reb.empty() ? std::string("-") : fmt_ms(median(reb))) << " |\n";
    }

    const auto medians = [](const std::vector<FrameSample>& frames, double FrameSample::*field) {
        std::vector<double> v;
        for (const FrameSample& f : frames)
            v.push_back(f.*field);
        return median(v);
    };
    const double wall =
        medians(world.incremental, &FrameSample::wall_ms) / medians(world.rebuild, &FrameSample::wall_ms);
    const double gpu =
        medians(world.incremental, &FrameSample::gpu_ms) / medians(world.rebuild, &FrameSample::gpu_ms);
    out << "\nIncremental / rebuild: " << fmt_ratio(wall) << " in wall time and " << fmt_ratio(gpu)
        << " in GPU time; the goal of at most " << fmt_ratio(kFrameGoal) << " is "
        << (wall <= kFrameGoal && gpu <= kFrameGoal   ? "met"
            : wall <= kFrameGoal || gpu <= kFrameGoal ? "met in one of the two"
                                                      : "not met")
        << ". Posing and uploading the character took "
        << fmt_ms(medians(world.incremental, &FrameSample::pose_ms))
        << " ms per frame (median, CPU, outside the timed step). The pools grew " << world.growths
        << " time(s) over the run, warm-up included.\n";
}

} // namespace

/// The Markdown body of the results block: heading, command, machine, the three sections and notes.
std::string render(const std::vector<TreeRow>& depth_rows, const std::vector<TreeRow>& byte_rows,
                   const std::vector<Voxelized>& grids, const WorldResult& world, std::uint64_t triangles,
                   const Plan& plan, const gust::gpu::DeviceInfo& device, const RunInfo& run) {
    std::ostringstream out;
    std::vector<std::string> notes;
    out << "## Sparse tree: build time, bytes and incremental frames (seed tables 2 and 3)"
        << heading_device(device) << "\n\n";
    out << "Command: `" << run.command << "`\n\n";
    out << "Machine: Vulkan device " << device.name << " (" << device.type << ", " << device.driver
        << "); CPU " << cpu_model() << ", " << usable_cores() << " usable cores. Run started " << run.started
        << " and took " << fmt_ms(ms_since(run.start) / 60000.0) << " min; 1-minute load average "
        << run.load_start << " at the start and " << load_average()
        << " at the end (a load above the core count means other processes shared the cores).\n\n";
    const auto fragments =
        std::find_if(grids.begin(), grids.end(), [&](const Voxelized& g) { return g.res == plan.depth_res; });
    if (fragments != grids.end()) render_depth(out, depth_rows, *fragments, triangles, plan, notes);
    render_bytes(out, grids, byte_rows, plan, notes);
    render_world(out, world, plan);
    if (!notes.empty()) {
        out << "\nNotes:\n\n";
        for (std::size_t i = 0; i < notes.size(); ++i)
            out << i + 1 << ". " << notes[i] << "\n";
    }
    if (device.type == "cpu")
        out << "\nThe seed's times are from an RTX 2070 Super; " << device.name
            << " is a CPU-emulated Vulkan device, so the absolute times here are not comparable with them, "
               "only their trends and the ratios.\n";
    return out.str();
}

} // namespace gust::bench::tree
