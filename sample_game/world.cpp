#include "world.hpp"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <gust/scene/import.hpp>
#include <gust/scene/primitives.hpp>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace sample {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
/// Half the edge of the square the grass grows in (m).
constexpr float kFieldHalf = 14.0f;
/// The valley: terrain this wide (m) in quads of 5 m, flat around the village.
constexpr float kValleySize = 1000.0f;
constexpr std::uint32_t kValleySamples = 200;
/// The ridge upwind of the village: its crest this far from the middle (m), this high and wide (m).
constexpr float kRidgeDistance = 130.0f, kRidgeHeight = 60.0f, kRidgeWidth = 35.0f;
/// The lee grove stands this far downwind of the crest (m).
constexpr float kLeeDistance = 60.0f;

/// Whether an object is the ground (the terrain or the bedrock under it): no obstacle, no footprint.
bool is_ground(const std::string& name) {
    return name == "ground" || name == "bedrock";
}

/// The valley around the village (docs/sample.md): flat at y = 0 within 60 m of the middle, a ridge across
/// the wind `upwind` of it, lower hills and a ridge downwind around it.
gust::TerrainDesc valley(glm::vec2 upwind) {
    const glm::vec2 across(-upwind.y, upwind.x);
    const glm::vec2 crest = kRidgeDistance * upwind;
    gust::TerrainDesc terrain;
    terrain.size = glm::vec2(kValleySize);
    terrain.samples = glm::uvec2(kValleySamples);
    terrain.features = {
        {crest - 160.0f * across, crest + 160.0f * across, kRidgeHeight, kRidgeWidth},
        {-220.0f * upwind - 250.0f * across, -220.0f * upwind + 250.0f * across, 30.0f, 50.0f},
        {-300.0f * upwind + 300.0f * across, -300.0f * upwind + 300.0f * across, 45.0f, 90.0f},
        {200.0f * upwind - 280.0f * across, 200.0f * upwind - 280.0f * across, 50.0f, 100.0f},
        {150.0f * across, 150.0f * across, 20.0f, 40.0f},
    };
    return terrain;
}

gust::Mesh load_or_throw(const std::filesystem::path& path) {
    gust::Result<gust::Mesh> mesh = gust::load_mesh(path);
    if (!mesh) throw std::runtime_error(mesh.message());
    return std::move(*mesh);
}

/// The palm file holds an island and a sea around the tree; keep the trunk and fronds only: triangles
/// near the trunk and above the island's crest (file units, which are metres).
gust::Mesh palm_only(const gust::Mesh& island) {
    const glm::vec2 trunk(0.1f, -0.6f);
    constexpr float kRadius = 3.0f, kCrest = 0.85f;
    gust::Mesh out;
    out.name = island.name;
    std::vector<std::uint32_t> remap(island.positions.size(), UINT32_MAX);
    for (std::size_t t = 0; t + 2 < island.indices.size(); t += 3) {
        glm::vec3 centroid(0.0f);
        float top = -1e30f;
        for (int k = 0; k < 3; ++k) {
            const glm::vec3 p = island.positions[island.indices[t + k]];
            centroid += p / 3.0f;
            top = std::max(top, p.y);
        }
        if (glm::length(glm::vec2(centroid.x, centroid.z) - trunk) > kRadius || top < kCrest) continue;
        for (int k = 0; k < 3; ++k) {
            std::uint32_t& slot = remap[island.indices[t + k]];
            if (slot == UINT32_MAX) {
                slot = static_cast<std::uint32_t>(out.positions.size());
                out.positions.push_back(island.positions[island.indices[t + k]] -
                                        glm::vec3(trunk.x, kCrest, trunk.y));
            }
            out.indices.push_back(slot);
        }
    }
    return out;
}

gust::Mat4 to_gust(const glm::mat4& m) {
    gust::Mat4 out;
    std::copy_n(glm::value_ptr(m), 16, out.m);
    return out;
}

gust::Vec3 to_gust(glm::vec3 v) {
    return {v.x, v.y, v.z};
}

glm::mat4 place(glm::vec3 position, float yaw, float scale) {
    return glm::scale(glm::rotate(glm::translate(glm::mat4(1.0f), position), yaw, glm::vec3(0, 1, 0)),
                      glm::vec3(scale));
}

/// Axis-aligned footprints (xz min, max) the grass avoids.
struct Footprint {
    glm::vec2 lo, hi;
};

} // namespace

std::size_t World::add_mesh(gust::Mesh mesh) {
    meshes_.push_back({std::move(mesh), nullptr, 0, {}});
    posed_.push_back(meshes_.back().mesh.positions);
    palettes_.emplace_back();
    return meshes_.size() - 1;
}

World::World(const std::filesystem::path& assets, const WorldSettings& settings) : settings_(settings) {
    const float heading = glm::radians(settings_.wind_heading_deg);
    const glm::vec2 upwind(-std::cos(heading), -std::sin(heading));
    terrain_ = valley(upwind);
    const gust::TerrainDesc& terrain = terrain_;
    const std::size_t ground = add_mesh(gust::make_terrain_mesh(terrain));
    objects_.push_back({"ground", ground, ObjectKind::Static, glm::mat4(1.0f), {0.32f, 0.42f, 0.22f}});
    // The terrain is an open sheet: under it, a block of rock keeps the air out of the hills (gust
    // voxelizes surfaces), as deep as the coarsest cascade reaches.
    const std::size_t rock = add_mesh(gust::make_box_mesh({-0.5f * kValleySize, -400.0f, -0.5f * kValleySize},
                                                          {0.5f * kValleySize, -0.25f, 0.5f * kValleySize}));
    objects_.push_back({"bedrock", rock, ObjectKind::Static, glm::mat4(1.0f), {0.35f, 0.33f, 0.3f}});

    struct Building {
        const char* file;
        glm::vec3 position;
        float yaw_deg, scale;
        glm::vec3 color;
    };
    const Building buildings[] = {
        {"architecture/building-garage.glb", {6.5f, 0.0f, -8.5f}, 0.0f, 5.0f, {0.62f, 0.55f, 0.48f}},
        {"architecture/building-small-a.glb", {-7.0f, 0.0f, -7.0f}, 90.0f, 4.0f, {0.70f, 0.66f, 0.60f}},
        {"architecture/building-small-c.glb", {7.5f, 0.0f, 6.0f}, 0.0f, 3.5f, {0.55f, 0.58f, 0.66f}},
    };
    for (const Building& b : buildings) {
        const std::size_t mesh = add_mesh(load_or_throw(assets / b.file));
        objects_.push_back(
            {b.file, mesh, ObjectKind::Static, place(b.position, glm::radians(b.yaw_deg), b.scale), b.color});
    }

    const std::size_t palm = add_mesh(palm_only(load_or_throw(assets / "foliage/PalmTree/PalmTree.gltf")));
    const glm::vec3 palms[] = {
        {-8.0f, 0.0f, 6.0f}, {-1.5f, 0.0f, -10.0f}, {10.5f, 0.0f, -0.5f}, {2.0f, 0.0f, 9.5f}};
    float palm_top = 0.0f;
    for (const glm::vec3& p : meshes_[palm].mesh.positions)
        palm_top = std::max(palm_top, p.y);
    std::vector<FoliageSeed> trees;
    for (std::size_t i = 0; i < std::size(palms); ++i) {
        const float scale = 1.2f + 0.15f * static_cast<float>(i % 2);
        WorldObject tree{"palm",
                         palm,
                         ObjectKind::Tree,
                         place(palms[i], 1.3f * static_cast<float>(i), scale),
                         {0.30f, 0.52f, 0.22f}};
        tree.sway_height = 0.3f * palm_top;
        tree.sway_length = 0.7f * palm_top;
        objects_.push_back(tree);
        // A crown is a stiffer, slower spring than a blade; its seed sits at the top of the tree.
        trees.push_back({glm::vec4(palms[i] + glm::vec3(0.0f, scale * palm_top, 0.0f), scale * palm_top),
                         glm::vec4(0.0f, 0.0f, 6.0f, 0.0f)});
    }

    // Groves far out: one on the ridge's crest, one in its lee, one in the valley downwind. Trees sway;
    // gust gets each one's trunk as a static solid, which every cascade voxelizes.
    const std::size_t grove_tree = add_mesh(load_or_throw(assets / "foliage/tree_detailed.glb"));
    const std::size_t trunk = add_mesh(gust::make_box_mesh({-0.3f, 0.0f, -0.3f}, {0.3f, 1.0f, 0.3f}));
    float tree_top = 0.0f;
    for (const glm::vec3& p : meshes_[grove_tree].mesh.positions)
        tree_top = std::max(tree_top, p.y);
    auto on_ground = [&](glm::vec2 xz) {
        return glm::vec3(xz.x, static_cast<float>(gust::terrain_height(terrain, xz.x, xz.y)), xz.y);
    };
    const glm::vec2 across(-upwind.y, upwind.x);
    const glm::vec2 crest = kRidgeDistance * upwind;
    stage_.upwind = glm::vec3(upwind.x, 0.0f, upwind.y);
    stage_.ridge_grove = on_ground(crest);
    stage_.lee_grove = on_ground(crest - kLeeDistance * upwind);
    const glm::vec2 groves[] = {crest, crest - kLeeDistance * upwind, -150.0f * upwind + 40.0f * across};
    std::mt19937 grove_rng(11u);
    std::uniform_real_distribution<float> spread(-1.0f, 1.0f);
    const char* grove_names[] = {"crest tree", "lee tree", "valley tree"};
    for (std::size_t g = 0; g < std::size(groves); ++g)
        for (int i = 0; i < 7; ++i) {
            const glm::vec2 middle = groves[g];
            // Along the crest, a few metres either side of the line across the wind.
            const glm::vec2 xz = middle +
                                 (12.0f * static_cast<float>(i - 3) + 3.0f * spread(grove_rng)) * across +
                                 4.0f * spread(grove_rng) * upwind;
            const glm::vec3 root = on_ground(xz) - glm::vec3(0.0f, 0.3f, 0.0f);
            const float height = 8.0f + 3.0f * (0.5f + 0.5f * spread(grove_rng));
            const float scale = height / tree_top;
            WorldObject tree{grove_names[g],
                             grove_tree,
                             ObjectKind::Tree,
                             place(root, 3.0f * spread(grove_rng), scale),
                             {0.22f, 0.45f, 0.2f}};
            tree.sway_height = 0.3f * tree_top;
            tree.sway_length = 0.7f * tree_top;
            objects_.push_back(tree);
            trees.push_back(
                {glm::vec4(root + glm::vec3(0.0f, height, 0.0f), height), glm::vec4(0.0f, 0.0f, 5.0f, 0.0f)});
            objects_.push_back(
                {"trunk",
                 trunk,
                 ObjectKind::Static,
                 glm::scale(glm::translate(glm::mat4(1.0f), root), glm::vec3(1.0f, 0.5f * height, 1.0f)),
                 {0.35f, 0.25f, 0.15f}});
        }

    const std::size_t fan_post = add_mesh(gust::make_box_mesh({-0.08f, 0.0f, -0.08f}, {0.08f, 1.2f, 0.08f}));
    objects_.push_back({"fan post",
                        fan_post,
                        ObjectKind::Prop,
                        place({-11.0f, 0.0f, 0.0f}, 0.0f, 1.0f),
                        {0.25f, 0.25f, 0.28f}});
    const std::size_t fan_head =
        add_mesh(gust::make_box_mesh({-0.15f, -0.55f, -0.55f}, {0.15f, 0.55f, 0.55f}));
    objects_.push_back({"fan", fan_head, ObjectKind::Prop, glm::mat4(1.0f), {0.8f, 0.2f, 0.15f}});

    auto load_character = [&](const char* file, const char* clip_name) {
        gust::Result<gust::AnimatedMesh> animated = gust::AnimatedMesh::load(assets / file);
        if (!animated) throw std::runtime_error(animated.message());
        auto shared = std::make_shared<gust::AnimatedMesh>(std::move(*animated));
        gust::Result<gust::AnimatedMesh::BoneSkin> bones = shared->bone_skin();
        if (!bones) throw std::runtime_error((assets / file).string() + ": " + bones.message());
        const std::size_t mesh = add_mesh(shared->rest_pose());
        meshes_[mesh].animation = shared;
        meshes_[mesh].clip = shared->find_clip(clip_name).value_or(0);
        meshes_[mesh].bones = std::move(*bones);
        return mesh;
    };
    objects_.push_back({"fox",
                        load_character("characters/Fox.glb", "Walk"),
                        ObjectKind::Skinned,
                        glm::mat4(1.0f),
                        {0.85f, 0.45f, 0.18f}});
    objects_.push_back({"cesium man",
                        load_character("characters/CesiumMan.glb", ""),
                        ObjectKind::Skinned,
                        glm::mat4(1.0f),
                        {0.35f, 0.45f, 0.75f}});
    objects_.push_back({"flying bunny",
                        add_mesh(load_or_throw(assets / "scans/bunny.ply")),
                        ObjectKind::Rigid,
                        glm::mat4(1.0f),
                        {0.85f, 0.82f, 0.78f}});

    for (const WorldObject& o : objects_) {
        if ((o.kind != ObjectKind::Static && o.kind != ObjectKind::Tree) || is_ground(o.name)) continue;
        Obstacle box{glm::vec3(std::numeric_limits<float>::max()),
                     glm::vec3(std::numeric_limits<float>::lowest())};
        for (const glm::vec3& p : meshes_[o.mesh].mesh.positions) {
            const glm::vec3 w(o.model * glm::vec4(p, 1.0f));
            box.lo = glm::min(box.lo, w);
            box.hi = glm::max(box.hi, w);
        }
        stage_.obstacles.push_back(box);
    }
    plant_grass();
    // Tree crowns follow the blades in the foliage state, in the order the trees were placed.
    for (WorldObject& o : objects_)
        if (o.kind == ObjectKind::Tree) {
            o.foliage_slot = static_cast<std::uint32_t>(foliage_.size());
            foliage_.push_back(trees[o.foliage_slot - grass_count_]);
        }
    update(0.0);
}

void World::plant_grass() {
    std::vector<Footprint> avoid;
    for (const WorldObject& o : objects_) {
        if (o.kind != ObjectKind::Static && o.kind != ObjectKind::Tree) continue;
        if (is_ground(o.name)) continue;
        const glm::vec3 c(o.model[3]);
        const float half =
            o.kind == ObjectKind::Tree ? 0.6f : 0.5f * glm::length(glm::vec3(o.model[0])) + 0.3f;
        avoid.push_back({glm::vec2(c.x, c.z) - half, glm::vec2(c.x, c.z) + half});
    }
    // A fixed seed: every run (and every test) grows the same field.
    std::mt19937 rng(7u);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    foliage_.clear();
    foliage_.reserve(settings_.grass_blades + 8);
    while (foliage_.size() < settings_.grass_blades) {
        const glm::vec2 p(kFieldHalf * (2.0f * unit(rng) - 1.0f), kFieldHalf * (2.0f * unit(rng) - 1.0f));
        const bool blocked = std::any_of(avoid.begin(), avoid.end(), [&](const Footprint& f) {
            return p.x > f.lo.x && p.x < f.hi.x && p.y > f.lo.y && p.y < f.hi.y;
        });
        if (blocked) continue;
        const float height = 0.35f + 0.4f * unit(rng);
        foliage_.push_back(
            {glm::vec4(p.x, 0.0f, p.y, height), glm::vec4(2.0f * kPi * unit(rng), 0.04f + 0.03f * unit(rng),
                                                          25.0f + 20.0f * unit(rng), unit(rng))});
    }
    grass_count_ = static_cast<std::uint32_t>(foliage_.size());
}

glm::vec3 World::ambient(double t) const {
    const float tf = static_cast<float>(t);
    // Two incommensurate sines give gusts that do not repeat visibly; the heading wanders a little.
    const float gust = 0.6f * std::sin(0.45f * tf) + 0.4f * std::sin(1.3f * tf + 1.7f);
    const float speed = std::max(0.0f, settings_.wind_speed * (1.0f + settings_.gustiness * gust));
    const float heading = glm::radians(settings_.wind_heading_deg + 12.0f * std::sin(0.2f * tf));
    return speed * glm::vec3(std::cos(heading), 0.0f, std::sin(heading));
}

gust::WindEmitter World::fan(double t) const {
    // An oscillating fan: it sweeps ±35° around +x every 8 s.
    const float sweep = glm::radians(35.0f) * std::sin(2.0f * kPi * static_cast<float>(t) / 8.0f);
    gust::WindEmitter fan;
    fan.type = gust::WindEmitterType::ConeMotor;
    fan.position = {-10.8f, 1.2f, 0.0f};
    fan.direction = {std::cos(sweep), 0.0f, std::sin(sweep)};
    fan.radius = 1.6f;
    fan.length = 6.0f;
    fan.strength = settings_.fan_on ? settings_.fan_strength : 0.0f;
    fan.falloff = 1.0f;
    return fan;
}

void World::update(double t) {
    const float tf = static_cast<float>(t) * settings_.walk_speed;
    // Poses a skinned object at clip time `clip_t` (looping) and notes when the clip wraps: that frame's
    // change of pose is a jump, which gust must not take for motion (a teleport).
    auto pose = [&](WorldObject& o, double clip_t) {
        const WorldMesh& mesh = meshes_[o.mesh];
        const double duration = mesh.animation->clip_duration(mesh.clip);
        const double lap = duration > 0.0 ? std::floor(clip_t / duration) : 0.0;
        o.wrapped = lap != o.lap;
        o.lap = lap;
        posed_[o.mesh].clear();
        mesh.animation->pose(mesh.clip, clip_t, true, posed_[o.mesh]);
        mesh.animation->bone_palette(mesh.clip, clip_t, true, palettes_[o.mesh]);
    };
    for (WorldObject& o : objects_) {
        if (o.name == "fox") {
            // A circle of radius 4.5 m around (0, 0, 2) at about 1.1 m/s, facing along the path (+z forward).
            const float a = 0.25f * tf;
            const glm::vec3 p(4.5f * std::cos(a), 0.0f, 2.0f + 4.5f * std::sin(a));
            const glm::vec3 forward(-std::sin(a), 0.0f, std::cos(a));
            o.model = place(p, std::atan2(forward.x, forward.z), 0.01f);
            stage_.fox = {p, forward};
            pose(o, 1.4 * tf);
        } else if (o.name == "cesium man") {
            // An ellipse around the middle of the field, walking at about 1 m/s. The file is z-up, but its
            // skin's joints carry the turn to y-up, so the posed vertices stand up already (+x forward).
            const float a = -0.16f * tf;
            const glm::vec3 p(1.0f + 7.0f * std::cos(a), 0.0f, -2.0f + 3.5f * std::sin(a));
            const glm::vec3 forward =
                glm::normalize(glm::vec3(7.0f * std::sin(a), 0.0f, -3.5f * std::cos(a)));
            o.model = place(p, std::atan2(forward.x, forward.z) - 0.5f * kPi, 1.0f);
            stage_.walker = {p, forward};
            pose(o, tf);
        } else if (o.name == "flying bunny") {
            // A figure of eight (Gerono's lemniscate) 9 m across at 2.5 m, bobbing, every 16 s.
            const float a = 2.0f * kPi * tf / 16.0f;
            const glm::vec3 p(9.0f * std::sin(a), 2.5f + 0.4f * std::sin(3.0f * a),
                              5.0f * std::sin(a) * std::cos(a));
            const glm::vec3 v(9.0f * std::cos(a), 0.0f, 5.0f * std::cos(2.0f * a));
            const glm::vec3 forward = glm::normalize(v);
            o.model = place(p, std::atan2(forward.x, forward.z), 0.12f);
            stage_.flyer = {p, forward};
            // The bunny carries a motor that blows backwards along its path, like a propeller.
            flyer_motor_.type = gust::WindEmitterType::CapsuleMotor;
            flyer_motor_.position = to_gust(p + glm::vec3(0.0f, 0.6f, 0.0f));
            flyer_motor_.direction = to_gust(-forward);
            flyer_motor_.length = 2.5f;
            flyer_motor_.radius = 1.0f;
            flyer_motor_.strength = settings_.flyer_motor_on ? 5.0f : 0.0f;
            flyer_motor_.falloff = 1.0f;
        } else if (o.name == "fan") {
            const gust::WindEmitter f = fan(t);
            o.model = place({f.position.x, f.position.y, f.position.z},
                            std::atan2(-f.direction.z, f.direction.x), 1.0f);
            stage_.fan = {f.position.x, f.position.y, f.position.z};
        }
    }
}

void World::attach(gust::System& wind) {
    gust_meshes_.assign(meshes_.size(), 0);
    for (WorldObject& o : objects_) {
        if (o.kind == ObjectKind::Tree || o.kind == ObjectKind::Prop) continue;
        if (!gust_meshes_[o.mesh]) {
            // gust skins the characters from their bone palettes: their mesh is the bind pose with a skin.
            const bool skinned = o.kind == ObjectKind::Skinned;
            const gust::AnimatedMesh::BoneSkin& bones = meshes_[o.mesh].bones;
            const std::vector<glm::vec3>& positions = skinned ? bones.bind : posed_[o.mesh];
            const gust::MeshSkin skin{bones.joint_count, bones.joints.data(), bones.weights.data()};
            gust::MeshDesc desc;
            desc.positions = &positions[0].x;
            desc.vertex_count = static_cast<std::uint32_t>(positions.size());
            desc.indices = meshes_[o.mesh].mesh.indices.data();
            desc.index_count = static_cast<std::uint32_t>(meshes_[o.mesh].mesh.indices.size());
            desc.deforming = skinned;
            desc.skin = skinned ? &skin : nullptr;
            if (gust::Outcome made = wind.create_mesh(desc, gust_meshes_[o.mesh]); !made)
                throw std::runtime_error("gust mesh " + o.name + ": " + made.message());
        }
        if (gust::Outcome placed = wind.create_instance(gust_meshes_[o.mesh], to_gust(o.model),
                                                        o.kind != ObjectKind::Static, o.instance);
            !placed)
            throw std::runtime_error("gust instance " + o.name + ": " + placed.message());
    }
}

gust::Outcome World::step_wind(gust::System& wind, float dt, double t) {
    for (const WorldObject& o : objects_) {
        if (o.kind == ObjectKind::Rigid || o.kind == ObjectKind::Skinned)
            if (gust::Outcome moved = wind.set_transform(o.instance, to_gust(o.model)); !moved) return moved;
        if (o.kind == ObjectKind::Skinned) {
            // The palette, not the posed vertices: gust skins them on the GPU.
            std::vector<gust::Mat4> palette;
            for (const glm::mat4& m : palettes_[o.mesh])
                palette.push_back(to_gust(m));
            if (gust::Outcome posed = wind.set_bones(gust_meshes_[o.mesh], palette.data(),
                                                     static_cast<std::uint32_t>(palette.size()), o.wrapped);
                !posed)
                return posed;
        }
    }
    const gust::WindEmitter emitters[] = {fan(t), flyer_motor_};
    if (gust::Outcome set = wind.set_emitters(emitters); !set) return set;
    if (gust::Outcome set = wind.set_ambient(to_gust(ambient(t))); !set) return set;
    return wind.step(dt);
}

glm::vec3 World::flight_at(double t) const {
    constexpr double kRadius = 300.0, kSpeed = 12.0;
    const double angle = kSpeed / kRadius * t;
    const double x = kRadius * std::cos(angle), z = kRadius * std::sin(angle);
    return glm::vec3(static_cast<float>(x), static_cast<float>(gust::terrain_height(terrain_, x, z) + 2.0),
                     static_cast<float>(z));
}

} // namespace sample
