// hello_wind: the smallest complete use of gust. It creates a wind System on its own Vulkan device,
// places a static ground and a moving box, blows an ambient wind and a fan, steps ten frames
// and prints the wind at a few points. Build it against an installed gust (examples/CMakeLists.txt):
//   cmake -S examples -B build-hello -DCMAKE_PREFIX_PATH=<gust's install prefix>
//   cmake --build build-hello && build-hello/hello_wind [--validation]
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <gust/gust.hpp>
#include <iterator>
#include <memory>

// Every gust call returns an Outcome; its message names the argument and the reason.
static bool ok(const gust::Outcome& outcome, const char* call) {
    if (!outcome) std::fprintf(stderr, "%s failed: %s\n", call, outcome.message().c_str());
    return static_cast<bool>(outcome);
}

static gust::Mat4 translation(float x, float y, float z) {
    gust::Mat4 m; // identity; column-major, so the translation is m[12..14]
    m.m[12] = x;
    m.m[13] = y;
    m.m[14] = z;
    return m;
}

int main(int argc, char** argv) {
    gust::SystemDesc desc; // no host device: gust creates its own (the best GPU, or GUST_DEVICE)
    desc.validation = argc > 1 && std::strcmp(argv[1], "--validation") == 0; // Khronos validation layer
    desc.domain.cells[0] = 32; // 32 x 16 x 32 wind cells of 1 m around the focus point
    desc.domain.cells[1] = 16;
    desc.domain.cells[2] = 32;
    desc.domain.focus = {0, 6, 0}; // the domain spans y from -2 m to 14 m
    desc.hooks.log = [](void*, gust::LogLevel level, const char* message) {
        const char* names[] = {"info", "warning", "error"};
        std::fprintf(stderr, "gust %s: %s\n", names[static_cast<int>(level)], message);
    };
    std::unique_ptr<gust::System> wind;
    if (!ok(gust::System::create(desc, wind), "System::create")) return 1;

    // A 40 m ground quad at y = 0 and a 2 m box around its origin, in mesh space (metres).
    const float ground_positions[] = {-20, 0, -20, 20, 0, -20, 20, 0, 20, -20, 0, 20};
    const std::uint32_t ground_indices[] = {0, 2, 1, 0, 3, 2};
    const float box_positions[] = {-1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1,
                                   -1, -1, 1,  1, -1, 1,  1, 1, 1,  -1, 1, 1};
    const std::uint32_t box_indices[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};
    gust::MeshDesc ground;
    ground.positions = ground_positions;
    ground.vertex_count = 4;
    ground.indices = ground_indices;
    ground.index_count = 6;
    gust::MeshDesc box = ground;
    box.positions = box_positions;
    box.vertex_count = 8;
    box.indices = box_indices;
    box.index_count = 36;

    gust::MeshId ground_mesh = 0, box_mesh = 0;
    gust::InstanceId ground_instance = 0, box_instance = 0;
    if (!ok(wind->create_mesh(ground, ground_mesh), "create_mesh(ground)") ||
        !ok(wind->create_mesh(box, box_mesh), "create_mesh(box)") ||
        !ok(wind->create_instance(ground_mesh, gust::Mat4{}, false, ground_instance),
            "create_instance(ground)") ||
        !ok(wind->create_instance(box_mesh, translation(-5, 1, 0), true, box_instance),
            "create_instance(box)"))
        return 1;

    // A 4 m/s breeze along +x, and a fan 5 m to the side blowing 8 m/s towards -z within 3 m of it.
    gust::WindEmitter fan;
    fan.type = gust::WindEmitterType::Directional;
    fan.position = {0, 2, 5};
    fan.direction = {0, 0, -1};
    fan.radius = 3.0f;
    fan.strength = 8.0f;
    if (!ok(wind->set_ambient({4, 0, 0}), "set_ambient") ||
        !ok(wind->set_emitters({&fan, 1}), "set_emitters"))
        return 1;

    // Ten frames at 60 Hz; the box drives along +x at 6 m/s and pushes the air in front of it.
    const int frames = 10;
    const float dt = 1.0f / 60.0f;
    for (int frame = 1; frame <= frames; ++frame) {
        const float x = -5.0f + 6.0f * dt * static_cast<float>(frame);
        if (!ok(wind->set_transform(box_instance, translation(x, 1, 0)), "set_transform") ||
            !ok(wind->step(dt), "step"))
            return 1;
    }
    std::printf("after %d frames: %llu solid voxels\n", frames,
                static_cast<unsigned long long>(wind->stats().voxels));

    // A batch of points in one GPU round trip (velocities in m/s, world space).
    const gust::Vec3 points[] = {{-10, 1, 0}, {-3, 1, 0}, {0, 2, 3}, {0, 8, 0}, {100, 0, 0}};
    gust::Vec3 velocities[std::size(points)];
    if (!ok(wind->query(points, velocities), "query")) return 1;
    for (std::size_t i = 0; i < std::size(points); ++i)
        std::printf("wind at (%g, %g, %g): (%.2f, %.2f, %.2f) m/s\n", points[i].x, points[i].y, points[i].z,
                    velocities[i].x, velocities[i].y, velocities[i].z);

    // One point as a foliage or cloth wind source takes it.
    gust::WindSample sample;
    if (!ok(wind->wind_at({0, 2, 3}, sample), "wind_at")) return 1;
    std::printf("wind_at (0, 2, 3): direction (%.2f, %.2f, %.2f), speed %.2f m/s, gust %.2f m/s\n",
                sample.direction.x, sample.direction.y, sample.direction.z, sample.speed, sample.gust);
    return 0;
}
