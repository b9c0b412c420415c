// Times the engine-facing System's costs, each A/B interleaved in one run:
// - System::sample (one thread, CPU) beside System::query (a blocking GPU round trip), and a step with the
//   snapshot against one without (docs/api.md "Wind snapshot");
// - a step of walking characters (CesiumMan, the Fox) skinned on the GPU from bones (set_bones) against one
//   from CPU-posed vertices (set_vertices): bytes handed over per frame and GPU time (docs/api.md "Skinning
//   from bones"). With --write it writes its block into docs/results.md.
//   gust_bench_snapshot [points] [--no-steps] [--skinning-only] [--write docs/results.md]
#include "bench_common.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <gust/gust.hpp>
#include <gust/scene/animated_mesh.hpp>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

std::unique_ptr<gust::System> make(std::uint32_t x, std::uint32_t y, std::uint32_t z, bool snapshot) {
    gust::SystemDesc desc;
    desc.domain.cells[0] = x;
    desc.domain.cells[1] = y;
    desc.domain.cells[2] = z;
    desc.snapshot = snapshot;
    std::unique_ptr<gust::System> system;
    if (const gust::Outcome o = gust::System::create(desc, system); !o) {
        std::fprintf(stderr, "create: %s\n", o.message().c_str());
        std::exit(1);
    }
    system->set_ambient({3.0f, 0.0f, 1.0f});
    return system;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

gust::Mat4 to_api(const glm::mat4& m) {
    gust::Mat4 out;
    std::copy_n(glm::value_ptr(m), 16, out.m);
    return out;
}

/// A character walking on the spot in a System: its clip played on, posed for one path or the other.
struct Walker {
    std::string file;
    gust::AnimatedMesh animation;
    gust::AnimatedMesh::BoneSkin skin;
    glm::mat4 place;
    gust::MeshId mesh = 0;
};

/// GPU milliseconds of one collected step: every pass, and the skinning pass alone.
struct StepMs {
    double total = 0.0, skin = 0.0;
};
StepMs step_ms(const gust::FrameStats& stats) {
    StepMs out;
    for (const auto& [pass, ms] : stats.ms) {
        out.total += ms;
        if (pass == "voxelize_skin") out.skin += ms;
    }
    return out;
}

/// One row of the skinning table: `walkers` in a System posed from vertices and in one posed from bones,
/// `frames` steps each, interleaved, after 3 untimed ones.
struct SkinRow {
    std::string scene;
    std::uint64_t vertices = 0, joints = 0, vertex_bytes = 0, bone_bytes = 0;
    double vertex_step = 0.0, bone_step = 0.0, skin = 0.0, vertex_wall = 0.0, bone_wall = 0.0;
};

gust::Status skin_row(const std::string& assets, const std::vector<std::string>& files, int frames,
                      SkinRow& row, std::string& device) {
    std::vector<Walker> walkers;
    for (std::size_t i = 0; i < files.size(); ++i) {
        auto path = gust::bench::asset_path(assets, files[i]);
        if (!path) return path.status();
        auto loaded = gust::AnimatedMesh::load(*path);
        if (!loaded) return loaded.status();
        auto skin = loaded->bone_skin();
        if (!skin) return skin.status();
        // The Fox's file is in centimetres, as the sample places it.
        const float scale = files[i].find("Fox") != std::string::npos ? 0.01f : 1.0f;
        const glm::mat4 place =
            glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(-2.0f + 4.0f * float(i), 0.01f, 0.0f)),
                       glm::vec3(scale));
        walkers.push_back({files[i], std::move(*loaded), std::move(*skin), place});
    }
    std::unique_ptr<gust::System> systems[2]; // [0]: posed vertices, [1]: bones
    std::vector<Walker> per_system[2] = {walkers, walkers};
    for (int s = 0; s < 2; ++s) {
        gust::SystemDesc desc;
        desc.domain.focus = {0.0f, 4.0f, 0.0f};
        if (gust::Outcome o = gust::System::create(desc, systems[s]); !o)
            return gust::Status::failure(o.message());
        systems[s]->set_ambient({3.0f, 0.0f, 1.0f});
        for (Walker& w : per_system[s]) {
            const gust::MeshSkin skin{w.skin.joint_count, w.skin.joints.data(), w.skin.weights.data()};
            gust::MeshDesc mesh;
            mesh.positions = &w.skin.bind[0].x;
            mesh.vertex_count = std::uint32_t(w.skin.bind.size());
            mesh.indices = w.animation.rest_pose().indices.data();
            mesh.index_count = std::uint32_t(w.animation.rest_pose().indices.size());
            mesh.deforming = true;
            mesh.skin = s == 1 ? &skin : nullptr;
            gust::InstanceId instance = 0;
            if (gust::Outcome o = systems[s]->create_mesh(mesh, w.mesh); !o)
                return gust::Status::failure(o.message());
            if (gust::Outcome o = systems[s]->create_instance(w.mesh, to_api(w.place), false, instance); !o)
                return gust::Status::failure(o.message());
        }
    }
    device = systems[0]->device_name();
    row.scene.clear();
    for (const Walker& w : walkers) {
        row.scene += (row.scene.empty() ? "" : " + ") + w.file.substr(w.file.rfind('/') + 1);
        row.vertices += w.skin.bind.size();
        row.joints += w.skin.joint_count;
    }
    // What each path hands gust per frame: set_vertices' float3 per vertex, set_bones' mat4 per joint (both
    // recorded into the frame's command buffer).
    row.vertex_bytes = row.vertices * 12;
    row.bone_bytes = row.joints * 64;
    std::vector<double> vertex_step, bone_step, skin, vertex_wall, bone_wall;
    std::vector<glm::vec3> posed;
    std::vector<glm::mat4> palette;
    std::vector<gust::Mat4> bones;
    const float dt = 1.0f / 30.0f;
    for (int f = -3; f < frames; ++f) {
        const double t = double(dt) * double(f + 3);
        for (int s = 0; s < 2; ++s) {
            for (Walker& w : per_system[s]) {
                gust::Outcome o;
                if (s == 0) {
                    w.animation.pose(0, t, true, posed);
                    o = systems[s]->set_vertices(w.mesh, &posed[0].x, std::uint32_t(posed.size()));
                } else {
                    w.animation.bone_palette(0, t, true, palette);
                    bones.clear();
                    for (const glm::mat4& m : palette)
                        bones.push_back(to_api(m));
                    o = systems[s]->set_bones(w.mesh, bones.data(), std::uint32_t(bones.size()));
                }
                if (!o) return gust::Status::failure(o.message());
            }
            const auto start = Clock::now();
            if (gust::Outcome o = systems[s]->step(dt); !o) return gust::Status::failure(o.message());
            const double wall = seconds_since(start) * 1e3;
            if (f < 0) continue;
            const StepMs ms = step_ms(systems[s]->stats());
            (s == 0 ? vertex_step : bone_step).push_back(ms.total);
            (s == 0 ? vertex_wall : bone_wall).push_back(wall);
            if (s == 1) skin.push_back(ms.skin);
        }
    }
    row.vertex_step = median(vertex_step);
    row.bone_step = median(bone_step);
    row.skin = median(skin);
    row.vertex_wall = median(vertex_wall);
    row.bone_wall = median(bone_wall);
    return {};
}

/// The skinning A/B: prints its table and, with `write`, puts it into that results file.
int skinning(const std::string& write, int argc, char** argv) {
    using gust::bench::fmt_ms;
    using gust::bench::grouped;
    const std::string started = gust::bench::utc_now(), load = gust::bench::load_average();
    const auto start = Clock::now();
    const int frames = 15;
    const std::vector<std::vector<std::string>> scenes = {{"characters/CesiumMan.glb"},
                                                          {"characters/Fox.glb"},
                                                          {"characters/CesiumMan.glb", "characters/Fox.glb"}};
    std::vector<SkinRow> rows;
    std::string device;
    for (const auto& files : scenes) {
        SkinRow row;
        if (gust::Status s = skin_row(GUST_ASSETS_DIR, files, frames, row, device); !s)
            return gust::bench::fail("gust_bench_snapshot", s.message());
        rows.push_back(row);
    }
    std::ostringstream out;
    const bool cpu = device.find("llvmpipe") != std::string::npos;
    out << "## Skinning from bones: bytes per frame and the skinning pass"
        << (cpu ? "" : " (on " + device + ")") << "\n\n";
    out << "Command: `" << gust::bench::command_line(argc, argv) << "`\n\n";
    out << "Machine: Vulkan device " << device << "; CPU " << gust::bench::cpu_model() << ", "
        << gust::bench::usable_cores() << " usable cores. Run started " << started << " and took "
        << fmt_ms(gust::bench::ms_since(start) / 60000.0) << " min; 1-minute load average " << load
        << " at the start and " << gust::bench::load_average() << " at the end.\n\n";
    out << "Each row places the characters (clip 0 looped, 1/30 s steps; the Fox at the sample's 0.01 scale) "
           "in two "
           "Systems of the default domain (32x16x32 cells of 1 m, 4 voxels per cell) and steps them in turn, "
        << frames
        << " timed steps each after 3 untimed ones: one System gets the poses as vertices posed on the CPU "
           "(`AnimatedMesh::pose`, `set_vertices`), the other the same poses as bone palettes "
           "(`AnimatedMesh::bone_palette`, `set_bones`), skinned on the GPU. Bytes per frame are what each "
           "path "
           "hands gust and records into the frame's command buffer: 12 a vertex, 64 a palette matrix (the "
           "palette holds every joint, plus the identity `bone_skin` adds). GPU ms sums a step's timestamp "
           "passes (`FrameStats::ms`, medians); the skinning pass is `voxelize_skin`.\n\n";
    out << "| Characters | Vertices | Palette matrices | Vertices B/frame | Bones B/frame | Bones / vertices "
           "| "
           "Step GPU ms, vertices | Step GPU ms, bones | Skinning pass ms | Skinning / step | Wall ms, "
           "vertices | "
           "Wall ms, bones |\n";
    out << "|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n";
    for (const SkinRow& r : rows)
        out << "| " << r.scene << " | " << grouped(r.vertices) << " | " << grouped(r.joints) << " | "
            << grouped(r.vertex_bytes) << " | " << grouped(r.bone_bytes) << " | "
            << gust::bench::fmt_ratio(double(r.bone_bytes) / double(r.vertex_bytes)) << " | "
            << fmt_ms(r.vertex_step) << " | " << fmt_ms(r.bone_step) << " | " << fmt_ms(r.skin) << " | "
            << gust::bench::fmt_ratio(r.skin / r.vertex_step) << " | " << fmt_ms(r.vertex_wall) << " | "
            << fmt_ms(r.bone_wall) << " |\n";
    const SkinRow& both = rows.back();
    out << "\nWith both characters the skinning pass took " << fmt_ms(both.skin) << " ms, "
        << gust::bench::fmt_ratio(both.skin / both.vertex_step) << " of a step posed from vertices ("
        << fmt_ms(both.vertex_step) << " ms GPU); the goal of at most one step's cost is "
        << (both.skin <= both.vertex_step ? "met" : "not met") << ". The bones hand over "
        << gust::bench::fmt_ratio(double(both.bone_bytes) / double(both.vertex_bytes))
        << " of the vertices' bytes per frame.\n";
    std::printf("%s", out.str().c_str());
    if (!write.empty())
        if (gust::Status s = gust::bench::write_block(write, cpu ? "skinning" : "skinning-gpu", out.str());
            !s)
            return gust::bench::fail("gust_bench_snapshot", s.message());
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    std::string write;
    bool skinning_only = false, no_steps = false;
    std::vector<char*> positional;
    for (int i = 1; i < argc; ++i) {
        if (std::strcmp(argv[i], "--write") == 0 && i + 1 < argc)
            write = argv[++i];
        else if (std::strcmp(argv[i], "--skinning-only") == 0)
            skinning_only = true;
        else if (std::strcmp(argv[i], "--no-steps") == 0)
            no_steps = true;
        else
            positional.push_back(argv[i]);
    }
    if (skinning_only) return skinning(write, argc, argv);
    const std::size_t count = !positional.empty() ? std::size_t(std::atol(positional[0])) : 1000000;
    auto system = make(32, 16, 32, true);
    system->step(1.0f / 60.0f);
    std::mt19937 random(1);
    std::uniform_real_distribution<float> x(-17.0f, 17.0f), y(-1.0f, 17.0f);
    std::vector<gust::Vec3> points(count), out(count);
    for (gust::Vec3& p : points)
        p = {x(random), y(random), x(random)};
    std::vector<double> sample_s, query_s;
    for (int r = 0; r < 5; ++r) {
        auto start = Clock::now();
        if (!system->sample(points, out)) return 1;
        sample_s.push_back(seconds_since(start));
        start = Clock::now();
        if (!system->query(points, out)) return 1;
        query_s.push_back(seconds_since(start));
    }
    std::printf("device: %s\n", system->device_name());
    std::printf("sample, one thread: %zu points in %.2f ms, %.1f M points/s\n", count, median(sample_s) * 1e3,
                double(count) / median(sample_s) / 1e6);
    std::printf("query (blocking):   %zu points in %.2f ms, %.1f M points/s\n", count, median(query_s) * 1e3,
                double(count) / median(query_s) / 1e6);
    const gust::Vec3 one[1] = {{0.0f, 4.0f, 0.0f}};
    gust::Vec3 one_out[1];
    std::vector<double> one_sample, one_query;
    for (int r = 0; r < 21; ++r) {
        auto start = Clock::now();
        system->sample(one, one_out);
        one_sample.push_back(seconds_since(start));
        start = Clock::now();
        system->query(one, one_out);
        one_query.push_back(seconds_since(start));
    }
    std::printf("one point: sample %.2f us, query %.2f us\n", median(one_sample) * 1e6,
                median(one_query) * 1e6);
    system.reset();
    if (no_steps) return 0;

    const std::uint32_t sizes[2][3] = {{32, 16, 32}, {64, 64, 64}};
    for (const auto& n : sizes) {
        auto without = make(n[0], n[1], n[2], false), with = make(n[0], n[1], n[2], true);
        for (int w = 0; w < 3; ++w) {
            without->step(1.0f / 60.0f);
            with->step(1.0f / 60.0f);
        }
        std::vector<double> a, b;
        for (int r = 0; r < 15; ++r) {
            auto start = Clock::now();
            without->step(1.0f / 60.0f);
            a.push_back(seconds_since(start));
            start = Clock::now();
            with->step(1.0f / 60.0f);
            b.push_back(seconds_since(start));
        }
        std::printf(
            "%ux%ux%u step: %.2f ms without the snapshot, %.2f ms with (%+.1f %%), 15 interleaved each\n",
            n[0], n[1], n[2], median(a) * 1e3, median(b) * 1e3, (median(b) / median(a) - 1.0) * 100.0);
    }
    return skinning(write, argc, argv);
}
