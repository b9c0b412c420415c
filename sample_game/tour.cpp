#include "tour.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sample {

namespace {

constexpr glm::vec3 kUp{0.0f, 1.0f, 0.0f};

/// An orbit camera `distance` from `target`, its eye in direction `towards_eye` (need not be unit length).
OrbitCamera looking_at(glm::vec3 target, glm::vec3 towards_eye, float distance) {
    const glm::vec3 d = glm::normalize(towards_eye);
    OrbitCamera camera;
    camera.target = target;
    camera.yaw = std::atan2(d.z, d.x);
    camera.pitch = std::asin(d.y);
    camera.distance = distance;
    return camera;
}

/// Whether the segment from `a` to `b` passes through `box` (slabs).
bool crosses(glm::vec3 a, glm::vec3 b, const Obstacle& box) {
    float enter = 0.0f, leave = 1.0f;
    for (int axis = 0; axis < 3; ++axis) {
        const float d = b[axis] - a[axis];
        if (std::abs(d) < 1e-6f) {
            if (a[axis] < box.lo[axis] || a[axis] > box.hi[axis]) return false;
            continue;
        }
        float t0 = (box.lo[axis] - a[axis]) / d, t1 = (box.hi[axis] - a[axis]) / d;
        if (t0 > t1) std::swap(t0, t1);
        enter = std::max(enter, t0);
        leave = std::min(leave, t1);
        if (enter > leave) return false;
    }
    return true;
}

/// `looking_at`, turned about the vertical by the least angle (in 20-degree steps, either way) that leaves
/// no obstacle between the eye and the target; unturned when every direction is blocked. A shot keeps
/// its own direction whenever that is clear, and turns only while something stands in the way.
OrbitCamera clear_view(const Stage& stage, glm::vec3 target, glm::vec3 towards_eye, float distance) {
    constexpr float kStep = 20.0f * std::numbers::pi_v<float> / 180.0f;
    // 0, then ±20°, ±40°, ... ±160°, then 180°: each direction once.
    for (int at = 0; at < 18; ++at) {
        const float a = (at % 2 == 0 ? -1.0f : 1.0f) * kStep * static_cast<float>((at + 1) / 2);
        const glm::vec3 d(std::cos(a) * towards_eye.x - std::sin(a) * towards_eye.z, towards_eye.y,
                          std::sin(a) * towards_eye.x + std::cos(a) * towards_eye.z);
        const OrbitCamera camera = looking_at(target, d, distance);
        const glm::vec3 eye = camera.eye();
        if (std::none_of(stage.obstacles.begin(), stage.obstacles.end(),
                         [&](const Obstacle& box) { return crosses(target, eye, box); }))
            return camera;
    }
    return looking_at(target, towards_eye, distance);
}

/// Right of a horizontal heading.
glm::vec3 right_of(glm::vec3 forward) {
    return {-forward.z, 0.0f, forward.x};
}

void overview(const Stage&, float u, OrbitCamera& camera, Views&) {
    camera.target = {0.0f, 1.0f, 0.0f};
    camera.yaw = 2.3f + 0.3f * u;
    camera.pitch = 0.5f;
    camera.distance = 26.0f - 4.0f * u;
}

void grass(const Stage& stage, float u, OrbitCamera& camera, Views&) {
    // To one side and a little ahead of the fox, closing in: the blades are as tall as its legs.
    const Actor& fox = stage.fox;
    camera = clear_view(stage, fox.position + glm::vec3(0.0f, 0.25f, 0.0f),
                        right_of(fox.forward) + 0.7f * fox.forward + 0.55f * kUp, 4.2f - 1.0f * u);
}

void fan(const Stage& stage, float u, OrbitCamera& camera, Views& views) {
    // From beside the fan and above, across its jet (it blows along +x, sweeping ±35°), with arrows of the
    // wind at the fan's height.
    camera = looking_at(stage.fan + glm::vec3(3.5f, -0.9f, 0.0f), glm::vec3(-0.35f - 0.2f * u, 0.8f, -0.75f),
                        9.0f);
    views.arrows = true;
    views.slice_height = stage.fan.y;
}

void wake(const Stage& stage, float, OrbitCamera& camera, Views& views) {
    // A fixed direction, so the flyer crosses the frame with its wake behind it, and the wind's speed
    // and arrows at the height of its motor (World: 0.6 m above the bunny).
    camera = clear_view(stage, stage.flyer.position, glm::vec3(0.25f, 0.9f, 1.0f), 9.0f);
    views.slice = true;
    views.arrows = true;
    views.slice_height = stage.flyer.position.y + 0.6f;
}

void tree(const Stage& stage, float u, OrbitCamera& camera, Views& views) {
    // gust's voxels instead of the triangles and grass, and only the tree nodes that change: those moving
    // meshes reach, made or freed (the ground's and the buildings' would hide them).
    // Seen from the middle of the field, turned where a palm or a building would stand in the way.
    const Actor& walker = stage.walker;
    const glm::vec3 inwards = glm::normalize(glm::vec3(-walker.position.x, 0.0f, -walker.position.z));
    // Close enough that the low preset's voxels (0.44 m) and nodes read as blocks around the walker.
    camera = clear_view(stage, walker.position + glm::vec3(0.0f, 0.7f, 0.0f),
                        inwards + 0.4f * walker.forward + 0.8f * kUp, 5.5f - 0.8f * u);
    views.triangles = false;
    views.grass = false;
    views.voxels = true;
    views.nodes = true;
    views.every_node = false;
}

void field(const Stage&, float u, OrbitCamera& camera, Views& views) {
    camera.target = {0.0f, 0.0f, 0.0f};
    camera.yaw = 2.0f + 0.25f * u;
    camera.pitch = 1.1f;
    camera.distance = 26.0f;
    views.slice = true;
    views.arrows = true;
    views.slice_height = 1.0f;
}

void valley(const Stage& stage, float u, OrbitCamera& camera, Views& views) {
    // High over the valley, from downwind and to the side, turning a little: the ridge across the wind,
    // each cascade's extent as a box and the wind's speed 8 m above the valley floor, every cascade's
    // blended.
    const glm::vec3 across(-stage.upwind.z, 0.0f, stage.upwind.x);
    camera = looking_at(0.15f * stage.ridge_grove, -stage.upwind + (0.5f + 0.3f * u) * across + 1.6f * kUp,
                        720.0f);
    views.grass = false;
    views.slice = true;
    views.cascades = true;
    views.slice_height = 8.0f;
}

void lee(const Stage& stage, float u, OrbitCamera& camera, Views&) {
    // From downwind of the ridge, a little to the side: the grove in its lee in front, the one on its crest
    // behind and above it, two rows across the frame.
    const glm::vec3 across(-stage.upwind.z, 0.0f, stage.upwind.x);
    const glm::vec3 middle = 0.5f * (stage.ridge_grove + stage.lee_grove);
    camera = looking_at(middle - glm::vec3(0.0f, 4.0f, 0.0f), -stage.upwind + 0.3f * across + 0.25f * kUp,
                        150.0f - 15.0f * u);
}

constexpr Shot kShots[] = {
    {"overview", "gust: wind on the GPU",
     "Wind simulated around the buildings, the walking fox and man, the flying bunny and the fan; the grass "
     "and palms bend in it.",
     2.0f, overview},
    {"grass", "Grass around a walker",
     "The fox is a moving solid: it pushes the air it walks through, and the grass around it bends.", 3.0f,
     grass},
    {"fan", "The fan",
     "A cone emitter sweeping 35 degrees either way every 8 s: the grass in its jet lies flat, the arrows "
     "show "
     "the wind at its height.",
     2.5f, fan},
    {"wake", "The flyer's wake",
     "The bunny carries a motor that blows backwards: the wind's speed and arrows at its height show the jet "
     "it leaves.",
     2.5f, wake},
    {"tree", "The voxel tree",
     "gust's voxels and the tree nodes that moving meshes reach: green made in the last second, grey kept, "
     "red freed as the walker moves.",
     3.0f, tree},
    {"field", "The wind field",
     "Wind speed 1 m above the ground, blue still to red 8 m/s, with arrows: shelter behind the buildings, "
     "the fan's jet.",
     2.5f, field},
    {"valley", "Cascades over the valley",
     "Three nested wind grids, each 4 times coarser, reach over the valley: their boxes, and the wind 8 m "
     "up with every cascade blended, the ridge standing through it.",
     3.0f, valley},
    {"lee", "The ridge's lee",
     "Trees on the ridge's crest sway in the full wind; the grove in its lee, sheltered by it, stands "
     "calmer.",
     3.0f, lee},
};

} // namespace

std::span<const Shot> tour_shots() {
    return kShots;
}

double tour_seconds() {
    double total = 0.0;
    for (const Shot& shot : kShots)
        total += shot.seconds;
    return total;
}

TourFrame tour_at(double t, const Stage& stage) {
    double into = std::fmod(std::max(t, 0.0), tour_seconds());
    TourFrame frame;
    for (std::size_t i = 0; i < std::size(kShots); ++i) {
        const Shot& shot = kShots[i];
        // The last shot takes what rounding leaves, so every t lands in one.
        if (into < shot.seconds || i + 1 == std::size(kShots)) {
            frame.index = i;
            frame.shot = &shot;
            shot.direct(stage, static_cast<float>(std::min(into / shot.seconds, 1.0)), frame.camera,
                        frame.views);
            break;
        }
        into -= shot.seconds;
    }
    return frame;
}

} // namespace sample
