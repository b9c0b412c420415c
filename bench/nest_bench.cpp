// How well a nest of cascades keeps what its coarser grids see (docs/solver.md "Cascades", issue 42): the
// wind at the player in a ridge's lee, with the ridge in the coarsest cascade only, against one grid of the
// coarsest cascade's extent and cells (and of half its cells); the wind over and behind the ridge in that
// grid against one three times taller; and the speed-up over a half-cylinder hill under the player against
// free-slip potential flow, for the nest and for one grid of twice the finest cells.
//   gust_bench_nest [--frames N] [--rows ridge,shelter,squeeze,hill] [--write docs/results.md]
#include "bench_common.hpp"
#include "mesh_desc.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <gust/gust.hpp>
#include <gust/scene/primitives.hpp>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr const char* kTool = "gust_bench_nest";
constexpr float kWind = 6.0f;

/// A closed cylinder of `radius` along z from -half to half, its axis at height 0 and x 0, with `sides`
/// flat sides.
gust::Mesh cylinder(float radius, float half, int sides) {
    gust::Mesh m;
    m.name = "cylinder";
    for (int i = 0; i < sides; ++i) {
        const float a = 2.0f * std::numbers::pi_v<float> * float(i) / float(sides);
        m.positions.push_back({radius * std::cos(a), radius * std::sin(a), -half});
        m.positions.push_back({radius * std::cos(a), radius * std::sin(a), half});
    }
    const auto c0 = std::uint32_t(m.positions.size());
    m.positions.push_back({0.0f, 0.0f, -half});
    m.positions.push_back({0.0f, 0.0f, half});
    for (int i = 0; i < sides; ++i) {
        const auto a = std::uint32_t(2 * i), b = std::uint32_t(2 * ((i + 1) % sides));
        m.indices.insert(m.indices.end(), {a, b, a + 1, b, b + 1, a + 1, c0, b, a, c0 + 1, a + 1, b + 1});
    }
    return m;
}

struct Domain {
    std::uint32_t cells[3] = {32, 16, 32};
    float cell_size = 1.0f;
    float focus_y = 7.0f;
    std::uint32_t cascades = 1, ratio = 4;
};

gust::Outcome make_system(const Domain& d, const std::vector<gust::Mesh>& solids,
                          std::unique_ptr<gust::System>& system) {
    gust::SystemDesc desc;
    for (int a = 0; a < 3; ++a)
        desc.domain.cells[a] = d.cells[a];
    desc.domain.cell_size = d.cell_size;
    desc.domain.focus = {0.0f, d.focus_y, 0.0f};
    desc.domain.cascades = d.cascades;
    desc.domain.ratio = d.ratio;
    if (gust::Outcome o = gust::System::create(desc, system); !o) return o;
    for (const gust::Mesh& m : solids) {
        gust::MeshId mesh = 0;
        gust::InstanceId id = 0;
        if (gust::Outcome o = system->create_mesh(gust::bench::desc_of(m), mesh); !o) return o;
        if (gust::Outcome o = system->create_instance(mesh, gust::Mat4{}, false, id); !o) return o;
    }
    return system->set_ambient({kWind, 0.0f, 0.0f});
}

/// The mean of each point's wind over `samples` frames from `first` to the last of `frames`, every `every`.
gust::Outcome mean_wind(const Domain& d, const std::vector<gust::Mesh>& solids, float dt, int frames,
                        int first, int every, const std::vector<gust::Vec3>& points,
                        std::vector<gust::Vec3>& mean) {
    std::unique_ptr<gust::System> system;
    if (gust::Outcome o = make_system(d, solids, system); !o) return o;
    std::vector<gust::Vec3> wind(points.size());
    mean.assign(points.size(), gust::Vec3{});
    int taken = 0;
    for (int f = 1; f <= frames; ++f) {
        if (gust::Outcome o = system->step(dt); !o) return o;
        if (f < first || (frames - f) % every != 0) continue;
        if (gust::Outcome o = system->query(points, wind); !o) return o;
        for (std::size_t i = 0; i < points.size(); ++i) {
            mean[i].x += wind[i].x;
            mean[i].y += wind[i].y;
            mean[i].z += wind[i].z;
        }
        ++taken;
    }
    for (gust::Vec3& m : mean) {
        m.x /= float(taken);
        m.y /= float(taken);
        m.z /= float(taken);
    }
    return {};
}

float mean_x(const std::vector<gust::Vec3>& v) {
    double s = 0.0;
    for (const gust::Vec3& w : v)
        s += w.x;
    return float(s / double(v.size()));
}

} // namespace

int main(int argc, char** argv) {
    int frames = 500;
    float dt = 0.1f;
    std::string write, rows = "ridge,squeeze,hill";
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--frames") == 0 && i + 1 < argc)
            frames = std::atoi(argv[++i]);
        else if (std::strcmp(argv[i], "--dt") == 0 && i + 1 < argc)
            dt = float(std::atof(argv[++i]));
        else if (std::strcmp(argv[i], "--rows") == 0 && i + 1 < argc)
            rows = argv[++i];
        else if (std::strcmp(argv[i], "--write") == 0 && i + 1 < argc)
            write = argv[++i];
        else
            return gust::bench::fail(kTool, std::string("unknown argument ") + argv[i] +
                                                " (usage: gust_bench_nest [--frames N] [--rows "
                                                "ridge,squeeze,hill] [--write FILE])");
    }
    if (frames < 10) return gust::bench::fail(kTool, "--frames must be at least 10");
    const auto has = [&](const char* row) { return rows.find(row) != std::string::npos; };
    std::ostringstream out;
    const gust::Mesh ground = gust::make_box_mesh({-4000.0f, -300.0f, -4000.0f}, {4000.0f, 0.0f, 4000.0f});
    const gust::Mesh ridge = gust::make_box_mesh({-160.0f, -10.0f, -4000.0f}, {-140.0f, 40.0f, 4000.0f});
    // The player's patch: 8 m around the focus, 2 to 8 m up.
    std::vector<gust::Vec3> player;
    for (float x = -8.0f; x <= 8.0f; x += 4.0f)
        for (float y = 2.0f; y <= 8.0f; y += 3.0f)
            for (float z = -8.0f; z <= 8.0f; z += 4.0f)
                player.push_back({x, y, z});
    Domain nest;
    nest.cascades = 3;
    Domain coarse;
    coarse.cell_size = 16.0f;
    Domain half = coarse;
    half.cell_size = 8.0f;
    for (std::uint32_t& c : half.cells)
        c *= 2;
    if (has("ridge")) {
        out << "| Ridge 150 m upwind, 3 cascades of ratio 4 | wind at the player m/s | x open "
               "|\n|--|--:|--:|\n";
        std::vector<std::pair<const char*, Domain>> grids = {{"the nest (1, 4, 16 m)", nest},
                                                             {"one grid of 16 m cells", coarse}};
        if (has("half")) grids.push_back({"one grid of 8 m cells", half});
        for (const auto& [name, d] : grids) {
            const auto start = gust::bench::Clock::now();
            std::vector<gust::Vec3> with, without;
            if (gust::Outcome o = mean_wind(d, {ground, ridge}, dt, frames, frames / 2, 10, player, with); !o)
                return gust::bench::fail(kTool, o.message());
            if (gust::Outcome o = mean_wind(d, {ground}, dt, 20, 10, 10, player, without); !o)
                return gust::bench::fail(kTool, o.message());
            out << "| " << name << " | " << mean_x(with) << " | " << mean_x(with) / mean_x(without) << " |\n";
            std::fprintf(stderr, "%s: %.0f s\n", name, gust::bench::ms_since(start) / 1000.0);
            std::printf("%s", out.str().c_str());
            std::fflush(stdout);
        }
    }
    if (has("squeeze")) {
        // Over and behind the ridge, 40-120 m up, from the ridge to 100 m past the player.
        std::vector<gust::Vec3> above;
        for (float x = -150.0f; x <= 100.0f; x += 10.0f)
            for (float y = 40.0f; y <= 120.0f; y += 10.0f)
                above.push_back({x, y, 0.0f});
        Domain tall = coarse;
        tall.cells[1] = 48;
        tall.focus_y = coarse.focus_y + 128.0f * 2.0f;
        out << "\n| Over and behind the ridge, 40-120 m up | mean speed m/s | 95th percentile "
               "|\n|--|--:|--:|\n";
        for (const auto& [name, d] : {std::pair{"one grid of 16 m cells, 135 m tall", coarse},
                                      std::pair{"the same, 3 times taller", tall}}) {
            std::vector<gust::Vec3> m;
            if (gust::Outcome o =
                    mean_wind(d, {ground, ridge}, dt, frames, frames * 7 / 10, frames / 10, above, m);
                !o)
                return gust::bench::fail(kTool, o.message());
            std::vector<float> speed;
            for (const gust::Vec3& w : m)
                speed.push_back(std::sqrt(w.x * w.x + w.y * w.y + w.z * w.z));
            std::sort(speed.begin(), speed.end());
            double s = 0.0;
            for (float v : speed)
                s += v;
            out << "| " << name << " | " << s / double(speed.size()) << " | "
                << speed[std::size_t(0.95 * double(speed.size() - 1))] << " |\n";
            std::printf("%s", out.str().c_str());
            std::fflush(stdout);
        }
    }
    if (has("hill")) {
        // A half-cylinder hill of radius R across the wind under the player: free-slip potential flow over it
        // is U (1 + R^2 / r^2) straight above its axis.
        constexpr float kR = 4.0f;
        const gust::Mesh hill = cylinder(kR, 4000.0f, 96);
        std::vector<gust::Vec3> crest;
        for (float y = 5.0f; y <= 9.0f; y += 1.0f)
            for (float z = -6.0f; z <= 6.0f; z += 3.0f)
                crest.push_back({0.0f, y, z});
        Domain twice;
        twice.cell_size = 2.0f;
        twice.cells[0] = twice.cells[2] = 64;
        twice.cells[1] = 32;
        twice.focus_y = 7.0f + 24.0f;
        out << "\n| Half-cylinder hill of 4 m under the player | wind 5-9 m above its axis / potential flow "
               "|\n|--|--:|\n";
        for (const auto& [name, d] :
             {std::pair{"the nest (1, 4, 16 m)", nest}, std::pair{"one grid of 2 m cells", twice}}) {
            std::vector<gust::Vec3> m;
            if (gust::Outcome o = mean_wind(d, {ground, hill}, dt, frames, frames / 2, 10, crest, m); !o)
                return gust::bench::fail(kTool, o.message());
            double s = 0.0;
            for (std::size_t i = 0; i < crest.size(); ++i)
                s += m[i].x / (kWind * (1.0f + kR * kR / (crest[i].y * crest[i].y)));
            out << "| " << name << " | " << s / double(crest.size()) << " |\n";
            std::printf("%s", out.str().c_str());
            std::fflush(stdout);
        }
    }
    if (!write.empty())
        if (gust::Status s = gust::bench::write_block(write, "nest", out.str()); !s)
            return gust::bench::fail(kTool, s.message());
    return 0;
}
