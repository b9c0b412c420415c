// The sample's parts that need no device: the quality presets, the tour's shots and the voxel faces.
#include "quality.hpp"
#include "tour.hpp"
#include "voxel_faces.hpp"
#include "world.hpp"

#include <algorithm>
#include <gtest/gtest.h>
#include <set>
#include <string>
#include <vector>

namespace {

using namespace sample;

/// The shots docs/sample.md lists, in order, with their lengths in seconds.
const std::vector<std::pair<std::string, double>> kDocumentedShots = {
    {"overview", 2.0}, {"grass", 3.0}, {"fan", 2.5},    {"wake", 2.5},
    {"tree", 3.0},     {"field", 2.5}, {"valley", 3.0}, {"lee", 3.0}};
constexpr double kTourSeconds = 21.5;

/// A stage with the actors somewhere in the field, heading in different directions.
Stage some_stage() {
    Stage stage;
    stage.fox = {{3.0f, 0.0f, 4.0f}, {-0.6f, 0.0f, 0.8f}};
    stage.walker = {{-2.0f, 0.0f, -5.0f}, {1.0f, 0.0f, 0.0f}};
    stage.flyer = {{5.0f, 2.7f, 1.0f}, {0.0f, 0.0f, -1.0f}};
    stage.fan = {-10.8f, 1.2f, 0.0f};
    // The ridge 130 m upwind (the wind blowing from 200 degrees), 60 m high, the lee grove 60 m behind it.
    stage.upwind = glm::normalize(glm::vec3(-0.94f, 0.0f, -0.34f));
    stage.ridge_grove = 130.0f * stage.upwind + glm::vec3(0.0f, 60.0f, 0.0f);
    stage.lee_grove = 70.0f * stage.upwind + glm::vec3(0.0f, 3.0f, 0.0f);
    return stage;
}

/// Whether two packed faces are the same side of the same voxel.
bool same_face(const VoxelFace& a, const VoxelFace& b) {
    return a.ij == b.ij && a.k_side == b.k_side;
}

/// Where `point` lands in the camera's picture: x and y in [-1, 1] are inside it.
glm::vec3 in_picture(const OrbitCamera& camera, glm::vec3 point) {
    const glm::vec4 clip = camera.view_proj(16.0f / 9.0f) * glm::vec4(point, 1.0f);
    return glm::vec3(clip) / clip.w;
}

double start_of(std::size_t shot) {
    double t = 0.0;
    for (std::size_t i = 0; i < shot; ++i)
        t += kDocumentedShots[i].second;
    return t;
}

} // namespace

TEST(SampleTour, playsTheDocumentedShotsInOrderAndStartsAgainAtTheEnd) {
    const Stage stage = some_stage();
    ASSERT_EQ(tour_shots().size(), kDocumentedShots.size());
    EXPECT_DOUBLE_EQ(tour_seconds(), kTourSeconds);
    for (std::size_t i = 0; i < kDocumentedShots.size(); ++i) {
        const double middle = start_of(i) + 0.5 * kDocumentedShots[i].second;
        const TourFrame frame = tour_at(middle, stage);
        EXPECT_EQ(frame.index, i);
        EXPECT_EQ(frame.shot->key, kDocumentedShots[i].first);
        EXPECT_GT(std::string(frame.shot->caption).size(), 20u) << frame.shot->key;
        EXPECT_EQ(tour_at(middle + kTourSeconds, stage).index, i) << "a second time round";
    }
    EXPECT_EQ(tour_at(start_of(1) - 0.01, stage).index, 0u);
    EXPECT_EQ(tour_at(start_of(1) + 0.01, stage).index, 1u);
}

TEST(SampleTour, everyShotMovesTheCamera) {
    const Stage stage = some_stage();
    std::set<std::pair<long, long>> eyes;
    for (std::size_t i = 0; i < kDocumentedShots.size(); ++i) {
        const glm::vec3 eye = tour_at(start_of(i) + 0.1, stage).camera.eye();
        eyes.insert({std::lround(eye.x * 10.0f), std::lround(eye.z * 10.0f)});
    }
    EXPECT_EQ(eyes.size(), kDocumentedShots.size()) << "two shots start from the same place";
}

TEST(SampleTour, closeShotsFrameTheirActorNearTheMiddle) {
    const Stage stage = some_stage();
    const TourFrame grass = tour_at(start_of(1) + 1.5, stage);
    EXPECT_LT(glm::distance(grass.camera.eye(), stage.fox.position), 5.0f) << "the fox should fill the frame";
    const glm::vec3 fox = in_picture(grass.camera, stage.fox.position + glm::vec3(0.0f, 0.3f, 0.0f));
    EXPECT_LT(std::max(std::abs(fox.x), std::abs(fox.y)), 0.2f);

    const TourFrame wake = tour_at(start_of(3) + 1.0, stage);
    const glm::vec3 flyer = in_picture(wake.camera, stage.flyer.position);
    EXPECT_LT(std::max(std::abs(flyer.x), std::abs(flyer.y)), 0.2f);
    // World puts the flyer's motor 0.6 m above the bunny; the wake is drawn at that height.
    EXPECT_FLOAT_EQ(wake.views.slice_height, stage.flyer.position.y + 0.6f);
    EXPECT_TRUE(wake.views.arrows);

    const TourFrame tree = tour_at(start_of(4) + 1.0, stage);
    const glm::vec3 walker = in_picture(tree.camera, stage.walker.position + glm::vec3(0.0f, 0.7f, 0.0f));
    EXPECT_LT(std::max(std::abs(walker.x), std::abs(walker.y)), 0.2f);
    // Close enough that the low preset's 0.44 m voxels and their nodes read as blocks.
    EXPECT_LT(glm::distance(tree.camera.eye(), stage.walker.position), 6.0f);
}

TEST(SampleTour, theValleyShotLooksDownOnEveryCascadeAndTheRidge) {
    const Stage stage = some_stage();
    for (double into : {0.1, 1.5, 2.9}) {
        const TourFrame valley = tour_at(start_of(6) + into, stage);
        EXPECT_EQ(valley.shot->key, std::string("valley"));
        EXPECT_TRUE(valley.views.cascades && valley.views.slice);
        EXPECT_GT(valley.camera.eye().y, 200.0f) << "a high view";
        // The low preset's coarsest cascade: 16 cells of 28 m, 448 m across, around the village; its
        // corners on the ground and the ridge all in the picture.
        for (glm::vec3 p :
             {glm::vec3(-224.0f, 0.0f, -224.0f), glm::vec3(224.0f, 0.0f, -224.0f),
              glm::vec3(-224.0f, 0.0f, 224.0f), glm::vec3(224.0f, 0.0f, 224.0f), stage.ridge_grove}) {
            const glm::vec3 seen = in_picture(valley.camera, p);
            EXPECT_LT(std::max(std::abs(seen.x), std::abs(seen.y)), 1.0f)
                << p.x << ", " << p.z << " at " << into;
            EXPECT_GT(seen.z, 0.0f);
            EXPECT_LT(seen.z, 1.0f) << "beyond the far plane";
        }
    }
}

TEST(SampleTour, theLeeShotFramesBothGrovesTheLeeOneInFront) {
    const Stage stage = some_stage();
    for (double into : {0.1, 1.5, 2.9}) {
        const TourFrame lee = tour_at(start_of(7) + into, stage);
        EXPECT_EQ(lee.shot->key, std::string("lee"));
        // The trees' crowns, about 9 m up.
        const glm::vec3 crest = in_picture(lee.camera, stage.ridge_grove + glm::vec3(0.0f, 9.0f, 0.0f));
        const glm::vec3 sheltered = in_picture(lee.camera, stage.lee_grove + glm::vec3(0.0f, 9.0f, 0.0f));
        for (const glm::vec3& seen : {crest, sheltered})
            EXPECT_LT(std::max(std::abs(seen.x), std::abs(seen.y)), 0.8f) << "at " << into;
        EXPECT_LT(glm::distance(lee.camera.eye(), stage.lee_grove),
                  glm::distance(lee.camera.eye(), stage.ridge_grove));
        EXPECT_LT(crest.y, sheltered.y) << "the crest grove above the lee grove in the picture (y down)";
    }
}

/// Whether the segment from `a` to `b` passes through `box`, by sampling it every centimetre.
bool hidden_by(glm::vec3 a, glm::vec3 b, const Obstacle& box) {
    const int steps = static_cast<int>(glm::distance(a, b) * 100.0f) + 1;
    for (int i = 0; i <= steps; ++i) {
        const glm::vec3 p = glm::mix(a, b, static_cast<float>(i) / static_cast<float>(steps));
        if (glm::all(glm::greaterThan(p, box.lo)) && glm::all(glm::lessThan(p, box.hi))) return true;
    }
    return false;
}

TEST(SampleTour, closeShotsLookPastABuildingInTheWay) {
    Stage stage = some_stage();
    const Stage open = stage;
    const struct {
        std::size_t shot;
        glm::vec3 actor;
    } close[] = {{1, stage.fox.position + glm::vec3(0.0f, 0.25f, 0.0f)},
                 {3, stage.flyer.position},
                 {4, stage.walker.position + glm::vec3(0.0f, 0.7f, 0.0f)}};
    for (const auto& c : close) {
        const double t = start_of(c.shot) + 1.0;
        // A 3 m box halfway along the line of sight the shot takes in the open.
        const glm::vec3 middle = glm::mix(c.actor, tour_at(t, open).camera.eye(), 0.5f);
        stage.obstacles = {{middle - 1.5f, middle + 1.5f}};
        ASSERT_TRUE(hidden_by(c.actor, tour_at(t, open).camera.eye(), stage.obstacles[0]));
        const TourFrame frame = tour_at(t, stage);
        EXPECT_FALSE(hidden_by(c.actor, frame.camera.eye(), stage.obstacles[0])) << frame.shot->key;
        const glm::vec3 seen = in_picture(frame.camera, c.actor);
        EXPECT_LT(std::max(std::abs(seen.x), std::abs(seen.y)), 0.2f) << frame.shot->key;
    }
}

TEST(SampleTour, eachShotTurnsOnTheViewsItsCaptionTalksAbout) {
    const Stage stage = some_stage();
    const Views overview = tour_at(start_of(0) + 1.0, stage).views;
    EXPECT_TRUE(overview.triangles && overview.grass);
    EXPECT_FALSE(overview.voxels || overview.nodes || overview.slice || overview.arrows);
    const Views tree = tour_at(start_of(4) + 1.0, stage).views;
    EXPECT_TRUE(tree.voxels && tree.nodes);
    EXPECT_FALSE(tree.triangles || tree.grass || tree.every_node);
    const Views field = tour_at(start_of(5) + 1.0, stage).views;
    EXPECT_TRUE(field.slice && field.arrows);
    EXPECT_FLOAT_EQ(field.slice_height, 1.0f);
    for (const Views& other : {overview, tree, field})
        EXPECT_FALSE(other.cascades);
    const Views lee = tour_at(start_of(7) + 1.0, stage).views;
    EXPECT_TRUE(lee.triangles && !lee.slice && !lee.cascades);
}

TEST(SampleWorld, theWalkersNeverPassThroughABuildingOrATree) {
    WorldSettings settings;
    settings.grass_blades = 100;
    World world(GUST_SAMPLE_ASSETS, settings);
    ASSERT_GE(world.stage().obstacles.size(), 7u) << "three buildings and four palms";
    // Two laps of the slower walker (CesiumMan's ellipse takes 39 s, the fox's circle 25 s).
    for (int frame = 0; frame <= 1600; ++frame) {
        const double t = 0.05 * frame;
        world.update(t);
        const Actor walkers[] = {world.stage().fox, world.stage().walker};
        for (const Actor& a : walkers)
            for (const Obstacle& box : world.stage().obstacles) {
                // The walker's body: 0.4 m around its feet, 1.7 m tall.
                const bool apart = a.position.x + 0.4f < box.lo.x || a.position.x - 0.4f > box.hi.x ||
                                   a.position.z + 0.4f < box.lo.z || a.position.z - 0.4f > box.hi.z ||
                                   a.position.y + 1.7f < box.lo.y || a.position.y > box.hi.y;
                ASSERT_TRUE(apart) << "at t = " << t << " s a walker at (" << a.position.x << ", "
                                   << a.position.z << ") is inside a box from (" << box.lo.x << ", "
                                   << box.lo.z << ") to (" << box.hi.x << ", " << box.hi.z << ")";
            }
    }
}

// gust gets the characters as bones (a skin once, a palette each frame); the palette poses the skin's bind
// positions where the renderer draws the CPU-posed vertices, up to float rounding.
TEST(SampleWorld, theCharactersReachGustAsBonesThatPoseThemAsDrawn) {
    WorldSettings settings;
    settings.grass_blades = 100;
    World world(GUST_SAMPLE_ASSETS, settings);
    int characters = 0;
    for (double t : {0.5, 3.25}) {
        world.update(t);
        for (const WorldObject& o : world.objects()) {
            if (o.kind != ObjectKind::Skinned) continue;
            ++characters;
            const gust::AnimatedMesh::BoneSkin& skin = world.meshes()[o.mesh].bones;
            const std::vector<glm::mat4>& palette = world.palette(o.mesh);
            const std::vector<glm::vec3>& drawn = world.posed(o.mesh);
            ASSERT_EQ(palette.size(), skin.joint_count) << o.name;
            ASSERT_EQ(skin.bind.size(), drawn.size()) << o.name;
            float far = 0.0f, size = 0.0f;
            for (std::size_t v = 0; v < drawn.size(); ++v) {
                glm::vec4 p(0.0f);
                for (std::size_t i = 4 * v; i < 4 * v + 4; ++i)
                    p += skin.weights[i] * (palette[skin.joints[i]] * glm::vec4(skin.bind[v], 1.0f));
                far = std::max(far, glm::length(glm::vec3(p) - drawn[v]));
                size = std::max(size, glm::length(drawn[v] - drawn[0]));
            }
            EXPECT_LT(far, 1e-5f * size) << o.name << " at t = " << t;
        }
    }
    EXPECT_EQ(characters, 4) << "the fox and CesiumMan, twice";
}

TEST(SampleQuality, autoPicksThePresetFromTheDeviceType) {
    EXPECT_EQ(quality_for_device(VK_PHYSICAL_DEVICE_TYPE_CPU), Quality::Low);
    EXPECT_EQ(quality_for_device(VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU), Quality::Medium);
    EXPECT_EQ(quality_for_device(VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU), Quality::Medium);
    EXPECT_EQ(quality_for_device(VK_PHYSICAL_DEVICE_TYPE_OTHER), Quality::Medium);
    EXPECT_EQ(quality_for_device(VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU), Quality::High);
    EXPECT_EQ(resolve(Quality::Auto, VK_PHYSICAL_DEVICE_TYPE_CPU), Quality::Low);
    EXPECT_EQ(resolve(Quality::High, VK_PHYSICAL_DEVICE_TYPE_CPU), Quality::High);
}

TEST(SampleQuality, theHighPresetIsAFineGridAndADenseField) {
    // The issue asks a discrete GPU for about 0.5 m cells, 4 voxels per cell and 64 or more cells across.
    const Detail high = preset(Quality::High), low = preset(Quality::Low);
    EXPECT_LE(high.cell_size, 0.5f);
    EXPECT_EQ(high.voxels_per_cell, 4u);
    EXPECT_GE(std::min(high.cells[0], high.cells[2]), 64u);
    EXPECT_GT(high.grass_blades, low.grass_blades);
    EXPECT_LT(high.cell_size / static_cast<float>(high.voxels_per_cell),
              low.cell_size / static_cast<float>(low.voxels_per_cell));
}

TEST(SampleQuality, overridesReplaceOnlyTheValuesTheyName) {
    DetailOverrides overrides;
    overrides.cells = std::array<std::uint32_t, 3>{16, 8, 16};
    overrides.grass_blades = 3000;
    const Detail medium = preset(Quality::Medium);
    const Detail d = apply(medium, overrides);
    EXPECT_EQ(d.cells, (std::array<std::uint32_t, 3>{16, 8, 16}));
    EXPECT_EQ(d.grass_blades, 3000u);
    EXPECT_EQ(d.cell_size, medium.cell_size);
    EXPECT_EQ(d.voxels_per_cell, medium.voxels_per_cell);
    EXPECT_EQ(d.max_cycles, medium.max_cycles);
}

TEST(SampleQuality, namesParseInAnyCaseAndOthersDoNot) {
    EXPECT_EQ(parse_quality("low"), Quality::Low);
    EXPECT_EQ(parse_quality("High"), Quality::High);
    EXPECT_EQ(parse_quality("AUTO"), Quality::Auto);
    EXPECT_FALSE(parse_quality("ultra").has_value());
    EXPECT_FALSE(parse_quality("").has_value());
    EXPECT_FALSE(parse_quality("lowest").has_value());
}

TEST(SampleVoxelFaces, aLoneVoxelShowsSixFacesAndNeighboursHideTheSidesTheyShare) {
    VoxelFaces finder;
    std::vector<VoxelFace> faces;
    const gust::VoxelCoord one[] = {{5, 6, 7}};
    finder.find(one, faces);
    ASSERT_EQ(faces.size(), 6u);
    std::set<std::uint32_t> sides;
    for (const VoxelFace& f : faces) {
        EXPECT_EQ(f.ij, 5u | 6u << 16);
        EXPECT_EQ(f.k_side & 0xffffu, 7u);
        sides.insert(f.k_side >> 16);
    }
    EXPECT_EQ(sides, (std::set<std::uint32_t>{0, 1, 2, 3, 4, 5}));

    // Two voxels side by side along x: 12 faces less the two they share.
    const gust::VoxelCoord pair[] = {{0, 0, 0}, {1, 0, 0}};
    finder.find(pair, faces);
    EXPECT_EQ(faces.size(), 10u);
    for (const VoxelFace& f : faces) {
        EXPECT_FALSE(same_face(f, pack_face(0, 0, 0, 1))) << "+x of the first voxel is shared";
        EXPECT_FALSE(same_face(f, pack_face(1, 0, 0, 0))) << "-x of the second voxel is shared";
    }
}

TEST(SampleVoxelFaces, aSolidCubeShowsOnlyItsSurface) {
    // A 3x3x3 block: 9 faces on each of its 6 sides, none inside; the centre voxel shows nothing.
    std::vector<gust::VoxelCoord> cube;
    for (std::uint32_t k = 10; k < 13; ++k)
        for (std::uint32_t j = 0; j < 3; ++j)
            for (std::uint32_t i = 20; i < 23; ++i)
                cube.push_back({i, j, k});
    VoxelFaces finder;
    std::vector<VoxelFace> faces;
    finder.find(cube, faces);
    EXPECT_EQ(faces.size(), 54u);
    for (const VoxelFace& f : faces)
        EXPECT_FALSE(f.ij == (21u | 1u << 16) && (f.k_side & 0xffffu) == 11u) << "the centre voxel is hidden";
    finder.find({}, faces);
    EXPECT_TRUE(faces.empty());
}

TEST(SampleQuality, everyPresetNestsCascadesThatTheShadersRead) {
    for (Quality q : {Quality::Low, Quality::Medium, Quality::High}) {
        const Detail d = preset(q);
        EXPECT_GE(d.cascades, 1u);
        EXPECT_LE(d.cascades, kMaxCascades) << "the sample's shaders bind kMaxCascades wind textures";
        EXPECT_TRUE(d.ratio == 2 || d.ratio == 4);
    }
    // The goal: three cascades of ratio 4 at the low preset, reaching 448 m across the valley.
    const Detail low = preset(Quality::Low);
    EXPECT_EQ(low.cascades, 3u);
    EXPECT_EQ(low.ratio, 4u);
    EXPECT_GE(static_cast<float>(low.cells[0]) * low.cell_size * 16.0f, 440.0f);
    DetailOverrides one;
    one.cascades = 1u;
    const Detail d = apply(low, one);
    EXPECT_EQ(d.cascades, 1u);
    EXPECT_EQ(d.cells, low.cells);
}

TEST(SampleWorld, theValleyHasARidgeUpwindWithGrovesOnItsCrestAndInItsLeeAndAFlatVillage) {
    WorldSettings settings;
    settings.grass_blades = 100;
    World world(GUST_SAMPLE_ASSETS, settings);
    const Stage& stage = world.stage();
    const float heading = glm::radians(settings.wind_heading_deg);
    EXPECT_GT(glm::dot(stage.upwind, -glm::vec3(std::cos(heading), 0.0f, std::sin(heading))), 0.99f);
    EXPECT_GT(stage.ridge_grove.y, 40.0f) << "the crest stands high";
    EXPECT_LT(stage.lee_grove.y, 0.3f * stage.ridge_grove.y) << "the lee grove stands low behind it";
    EXPECT_LT(glm::length(stage.lee_grove), glm::length(stage.ridge_grove))
        << "between the ridge and the village";
    // Both groves inside the low preset's coarsest cascade (224 m either side of the village).
    for (glm::vec3 g : {stage.ridge_grove, stage.lee_grove})
        EXPECT_LT(std::max(std::abs(g.x), std::abs(g.z)), 210.0f);
    const auto ground = std::find_if(world.objects().begin(), world.objects().end(),
                                     [](const WorldObject& o) { return o.name == "ground"; });
    ASSERT_NE(ground, world.objects().end());
    const gust::Mesh& terrain = world.meshes()[ground->mesh].mesh;
    EXPECT_LT(terrain.indices.size() / 3, 100000u) << "a modest mesh that lavapipe draws at the tour's rate";
    float span = 0.0f;
    for (const glm::vec3& p : terrain.positions) {
        span = std::max(span, std::abs(p.x));
        // The village and the walkers' paths stay on flat ground.
        if (std::max(std::abs(p.x), std::abs(p.z)) < 30.0f) {
            EXPECT_LT(std::abs(p.y), 0.05f) << p.x << ", " << p.z;
        }
    }
    EXPECT_GE(span, 450.0f) << "about 1 km across";
    int crest = 0, lee = 0;
    for (const WorldObject& o : world.objects()) {
        crest += o.name == "crest tree";
        lee += o.name == "lee tree";
    }
    EXPECT_GE(crest, 5);
    EXPECT_GE(lee, 5);
}
