// What nested cascades cost a frame (docs/solver.md "Cascades"), A/B in one run: Systems of 1 cascade and of
// more, at the sample's low preset or the grid given, over the same ground, buildings and a circling box,
// stepped in turn; the mean over whole schedules of dispatches, wall time and GPU time (the sum of every
// timed pass, the coarser cascades' included) a frame, and their ratio to one cascade.
//   gust_bench_cascades [--frames N] [--cells X,Y,Z] [--cell-size M] [--write docs/results.md]
#include "bench_common.hpp"
#include "mesh_desc.hpp"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <gust/gust.hpp>
#include <gust/scene/primitives.hpp>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr const char* kTool = "gust_bench_cascades";

/// The finest grid of every System (default: the sample's low preset, which a CPU device gets,
/// sample_game/quality.cpp).
struct Grid {
    std::uint32_t cells[3] = {16, 8, 16};
    float cell_size = 1.75f;
    float extent() const { return float(cells[0]) * cell_size; }
};

struct Nest {
    std::uint32_t cascades = 1, ratio = 4;
    std::unique_ptr<gust::System> system;
    gust::InstanceId mover = 0;
    double wall_ms = 0.0, gpu_ms = 0.0, dispatches = 0.0, stages = 0.0;
};

gust::Mat4 translation(float x, float y, float z) {
    gust::Mat4 m;
    m.m[12] = x;
    m.m[13] = y;
    m.m[14] = z;
    return m;
}

gust::Outcome build(const Grid& grid, Nest& nest) {
    gust::SystemDesc desc;
    for (int a = 0; a < 3; ++a)
        desc.domain.cells[a] = grid.cells[a];
    desc.domain.cell_size = grid.cell_size;
    desc.domain.focus = {0.0f, 0.5f * float(grid.cells[1]) * grid.cell_size - 1.0f, 0.0f};
    desc.domain.cascades = nest.cascades;
    desc.domain.ratio = nest.ratio;
    if (gust::Outcome o = gust::System::create(desc, nest.system); !o) return o;
    gust::System& s = *nest.system;
    static const gust::Mesh ground =
        gust::make_box_mesh({-2000.0f, -100.0f, -2000.0f}, {2000.0f, 0.0f, 2000.0f});
    static const gust::Mesh house = gust::make_box_mesh({-3.0f, 0.0f, -3.0f}, {3.0f, 5.0f, 3.0f});
    static const gust::Mesh crate = gust::make_box_mesh({-0.6f, -0.6f, -0.6f}, {0.6f, 0.6f, 0.6f});
    gust::MeshId g = 0, h = 0, c = 0;
    gust::InstanceId id = 0;
    if (gust::Outcome o = s.create_mesh(gust::bench::desc_of(ground), g); !o) return o;
    if (gust::Outcome o = s.create_mesh(gust::bench::desc_of(house), h); !o) return o;
    if (gust::Outcome o = s.create_mesh(gust::bench::desc_of(crate), c); !o) return o;
    if (gust::Outcome o = s.create_instance(g, gust::Mat4{}, false, id); !o) return o;
    for (float x : {-40.0f, -10.0f, 25.0f, 90.0f, 300.0f})
        if (gust::Outcome o = s.create_instance(h, translation(x, 0.0f, 0.5f * x), false, id); !o) return o;
    if (gust::Outcome o = s.create_instance(c, translation(4.0f, 1.0f, 0.0f), true, nest.mover); !o) return o;
    return s.set_ambient({5.0f, 0.0f, 2.0f});
}

gust::Outcome step(Nest& nest, int frame, bool timed) {
    const float a = 0.05f * float(frame);
    if (gust::Outcome o =
            nest.system->set_transform(nest.mover, translation(4.0f * std::cos(a), 1.0f, 4.0f * std::sin(a)));
        !o)
        return o;
    const auto start = gust::bench::Clock::now();
    if (gust::Outcome o = nest.system->step(1.0f / 30.0f); !o) return o;
    if (!timed) return {};
    nest.wall_ms += gust::bench::ms_since(start);
    nest.dispatches += double(nest.system->stats().dispatches);
    nest.stages += double(nest.system->stats().stages);
    for (const auto& [pass, ms] : nest.system->stats().ms)
        nest.gpu_ms += ms;
    return {};
}

} // namespace

int main(int argc, char** argv) {
    int frames = 128;
    std::string write;
    Grid grid;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
            frames = std::atoi(argv[++i]);
        } else if (std::strcmp(argv[i], "--cells") == 0 && i + 1 < argc) {
            if (std::sscanf(argv[++i], "%u,%u,%u", &grid.cells[0], &grid.cells[1], &grid.cells[2]) != 3)
                return gust::bench::fail(kTool, "--cells takes X,Y,Z");
        } else if (std::strcmp(argv[i], "--cell-size") == 0 && i + 1 < argc) {
            grid.cell_size = float(std::atof(argv[++i]));
        } else if (std::strcmp(argv[i], "--write") == 0 && i + 1 < argc) {
            write = argv[++i];
        } else {
            return gust::bench::fail(kTool, std::string("unknown argument ") + argv[i] +
                                                " (usage: gust_bench_cascades [--frames N] [--cells X,Y,Z] "
                                                "[--cell-size M] [--write FILE])");
        }
    }
    if (frames < 1) return gust::bench::fail(kTool, "--frames must be at least 1");
    if (!(grid.cell_size > 0.0f)) return gust::bench::fail(kTool, "--cell-size must be positive");
    const std::string started = gust::bench::utc_now(), load = gust::bench::load_average();
    const auto start = gust::bench::Clock::now();
    std::vector<Nest> nests(5);
    const std::uint32_t shapes[5][2] = {{1, 4}, {2, 4}, {3, 4}, {4, 4}, {3, 2}};
    for (std::size_t i = 0; i < nests.size(); ++i) {
        nests[i].cascades = shapes[i][0];
        nests[i].ratio = shapes[i][1];
    }
    for (Nest& n : nests)
        if (gust::Outcome o = build(grid, n); !o) return gust::bench::fail(kTool, o.message());
    // Untimed frames first (pipelines, pools, the first static voxels), then the Systems in turn.
    constexpr int kWarm = 8;
    for (int f = 0; f < kWarm + frames; ++f)
        for (Nest& n : nests)
            if (gust::Outcome o = step(n, f, f >= kWarm); !o) return gust::bench::fail(kTool, o.message());
    const std::string device = nests[0].system->device_name();
    const bool cpu = device.find("llvmpipe") != std::string::npos;

    std::ostringstream out;
    out << "## Cascades: what a frame costs" << (cpu ? "" : " (on " + device + ")") << "\n\n";
    out << "Command: `" << gust::bench::command_line(argc, argv) << "`\n\n";
    out << "Machine: Vulkan device " << device << "; CPU " << gust::bench::cpu_model() << ", "
        << gust::bench::usable_cores() << " usable cores. Run started " << started << " and took "
        << gust::bench::fmt_ms(gust::bench::ms_since(start) / 60000.0) << " min; 1-minute load average "
        << load << " at the start and " << gust::bench::load_average() << " at the end.\n\n";
    out << "Each row is a System of " << grid.cells[0] << "x" << grid.cells[1] << "x" << grid.cells[2]
        << " cells of " << gust::bench::fmt_ms(grid.cell_size)
        << " m in its finest cascade (4 voxels a cell, 2 V-cycles a step) over a 4 km ground, five houses "
           "from 10 m to 300 m out and a crate circling 4 m from the focus, in a 5.4 m/s wind. The Systems "
           "step in turn, "
        << frames << " timed frames of 1/30 s each after " << kWarm
        << " untimed ones; the columns are means over the timed frames, which hold whole schedules of the "
           "coarser cascades (cascade k steps every ratio^k frames). GPU ms is the sum of the frame's timed "
           "passes (FrameStats::ms, the coarser cascade's `cascade_` passes included).\n\n";
    out << "| Cascades | Ratio | Outer extent m | Dispatches a frame | Stages a frame | x one cascade | Wall "
           "ms "
           "a frame | x one cascade | GPU ms a frame | x one cascade |\n";
    out << "|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    const double base_d = nests[0].dispatches / frames, base_ms = nests[0].wall_ms / frames,
                 base_gpu = nests[0].gpu_ms / frames;
    for (const Nest& n : nests) {
        const double d = n.dispatches / frames, ms = n.wall_ms / frames, gpu = n.gpu_ms / frames;
        const double extent = grid.extent() * std::pow(double(n.ratio), double(n.cascades - 1));
        out << "| " << n.cascades << " | " << n.ratio << " | " << gust::bench::fmt_ms(extent) << " | "
            << gust::bench::fmt_ms(d) << " | " << gust::bench::fmt_ratio(d / base_d) << " | "
            << gust::bench::fmt_ms(n.stages / frames) << " | " << gust::bench::fmt_ms(ms) << " | "
            << gust::bench::fmt_ratio(ms / base_ms) << " | " << gust::bench::fmt_ms(gpu) << " | "
            << gust::bench::fmt_ratio(gpu / base_gpu) << " |\n";
    }
    const Nest& four = nests[3];
    const double ratio = (four.wall_ms / frames) / base_ms, four_gpu = four.gpu_ms / frames;
    out << "\n4 cascades of ratio 4 cost " << gust::bench::fmt_ratio(ratio)
        << " of one cascade's wall time a frame; the goal, at most 1.6x, is "
        << (ratio <= 1.6 ? "met" : "not met") << ". Their GPU time is " << gust::bench::fmt_ms(four_gpu)
        << " ms a frame";
    const bool goal_grid =
        grid.cells[0] == 64 && grid.cells[1] == 32 && grid.cells[2] == 64 && grid.cell_size == 0.5f;
    if (!cpu && goal_grid)
        out << "; the goal at this grid on a GPU, at most 0.5 ms, is "
            << (four_gpu <= 0.5 ? "met" : "not met");
    out << ".\n";
    std::printf("%s", out.str().c_str());
    if (!write.empty())
        if (gust::Status s = gust::bench::write_block(write, cpu ? "cascades" : "cascades-gpu", out.str());
            !s)
            return gust::bench::fail(kTool, s.message());
    return 0;
}
