// gust's own answer for test_box.gd's scene (and the Godot 4 extension's test_box.gd, whose node has 4
// voxels a cell and steps every physics frame), through gust's C++ API alone: the same domain, box, ambient
// wind and steps. Reads the points and Godot's velocities that test_box.gd wrote and fails unless every
// velocity is within 1 % of gust's (plus 1 mm/s for speeds near zero).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <gust/gust.hpp>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 2 && argc != 4) {
        std::fprintf(stderr, "usage: gust_godot_reference WIND_TXT [VOXELS_PER_CELL STEPS] (default 2 20)\n");
        return 2;
    }
    const std::uint32_t voxels_per_cell = argc == 4 ? std::uint32_t(std::atoi(argv[2])) : 2;
    const int steps = argc == 4 ? std::atoi(argv[3]) : 20;
    std::ifstream in(argv[1]);
    std::vector<gust::Vec3> points, godot_wind;
    gust::Vec3 p, v;
    while (in >> p.x >> p.y >> p.z >> v.x >> v.y >> v.z) {
        points.push_back(p);
        godot_wind.push_back(v);
    }
    if (points.empty()) {
        std::fprintf(stderr, "%s: no points\n", argv[1]);
        return 1;
    }
    gust::SystemDesc desc; // test_box.gd: GustWind at the origin, quality medium (the default settings)
    desc.domain.cells[0] = 16;
    desc.domain.cells[1] = 8;
    desc.domain.cells[2] = 16;
    desc.domain.cell_size = 0.5f;
    desc.domain.voxels_per_cell = voxels_per_cell;
    desc.snapshot = true;
    std::unique_ptr<gust::System> system;
    if (gust::Outcome o = gust::System::create(desc, system); !o) {
        std::fprintf(stderr, "create: %s\n", o.message().c_str());
        return 1;
    }
    // A 2 m cube centred on the origin (Godot's CubeMesh of size 2).
    const float c[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                           {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    const std::uint32_t idx[36] = {0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 0, 4, 5, 0, 5, 1,
                                   3, 2, 6, 3, 6, 7, 0, 3, 7, 0, 7, 4, 1, 5, 6, 1, 6, 2};
    gust::MeshDesc mesh;
    mesh.positions = &c[0][0];
    mesh.vertex_count = 8;
    mesh.indices = idx;
    mesh.index_count = 36;
    gust::MeshId mesh_id = 0;
    gust::InstanceId instance = 0;
    if (!system->create_mesh(mesh, mesh_id) ||
        !system->create_instance(mesh_id, gust::Mat4{}, false, instance) || !system->set_ambient({3, 0, 0})) {
        std::fprintf(stderr, "scene setup failed\n");
        return 1;
    }
    for (int i = 0; i < steps; ++i) {
        if (gust::Outcome o = system->step(1.0f / 60.0f); !o) {
            std::fprintf(stderr, "step: %s\n", o.message().c_str());
            return 1;
        }
    }
    std::vector<gust::Vec3> own(points.size());
    if (gust::Outcome o = system->sample(points, own); !o) {
        std::fprintf(stderr, "sample: %s\n", o.message().c_str());
        return 1;
    }
    int bad = 0;
    double worst = 0.0, disturbed = 0.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        const gust::Vec3 &a = godot_wind[i], &b = own[i];
        const double diff = std::hypot(a.x - b.x, a.y - b.y, a.z - b.z);
        const double ref = std::hypot(b.x, b.y, b.z);
        worst = std::max(worst, diff / std::max(ref, 1e-3));
        disturbed = std::max(disturbed, std::hypot(b.x - 3.0, b.y, b.z));
        if (!(diff <= 0.01 * ref + 1e-3)) {
            if (++bad <= 5) {
                std::fprintf(stderr, "at (%g %g %g): Godot (%g %g %g), gust (%g %g %g)\n", points[i].x,
                             points[i].y, points[i].z, a.x, a.y, a.z, b.x, b.y, b.z);
            }
        }
    }
    std::printf(
        "%zu points, %d beyond 1 %%, worst relative difference %.3g, largest deviation from the ambient "
        "wind %.3g m/s\n",
        points.size(), bad, worst, disturbed);
    // The box must matter, or agreeing would prove nothing about obstacles.
    if (disturbed < 0.3) {
        std::fprintf(stderr, "the box left the wind at the ambient 3 m/s: the scene tests nothing\n");
        return 1;
    }
    return bad == 0 ? 0 : 1;
}
