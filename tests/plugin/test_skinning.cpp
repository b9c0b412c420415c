// Skinning from bones (MeshDesc::skin, System::set_bones) against the CPU-posed path (set_vertices): a bar of
// two bones bending is posed on the CPU by the shader's own blend (skin_io.h) and handed to one System as
// vertices, and to another as a bone palette. Both must voxelize the same voxels and blow the same wind,
// frame after frame, teleports included; so must the sample's Fox and CesiumMan, posed by AnimatedMesh. Bad
// skins and palettes are refused and the System keeps working.
#include "system_test_support.hpp"
#include "voxelizer/skin_io.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <gust/scene/animated_mesh.hpp>
#include <limits>
#include <span>
#include <tuple>
#include <vector>

namespace gust::test {
namespace {

Mat4 to_api(const glm::mat4& m) {
    Mat4 out;
    std::copy_n(glm::value_ptr(m), 16, out.m);
    return out;
}

/// A square bar along x, [0, 4] m long and 0.62 m thick, in 8 segments (rings of 4 vertices) with end caps.
/// Joint 0 holds its left end, joint 1 (pivoting at x = 2) its right end, blended linearly over [1, 3];
/// joint 2 exists but moves nothing, so the palette has 3 matrices. Its faces lie off the voxel planes.
struct Bar {
    static constexpr int kRings = 9;
    static constexpr std::uint32_t kJoints = 3;
    std::vector<float> bind;
    std::vector<std::uint32_t> indices;
    std::vector<std::uint16_t> joints;
    std::vector<float> weights;

    Bar() {
        const float h = 0.31f;
        const float corner[4][2] = {{-h, -h}, {h, -h}, {h, h}, {-h, h}};
        for (int r = 0; r < kRings; ++r) {
            const float x = 4.0f * float(r) / float(kRings - 1);
            const float w1 = std::clamp((x - 1.0f) / 2.0f, 0.0f, 1.0f);
            for (const auto& c : corner) {
                bind.insert(bind.end(), {x, c[0], c[1]});
                joints.insert(joints.end(), {0, 1, 2, 0});
                weights.insert(weights.end(), {1.0f - w1, w1, 0.0f, 0.0f});
            }
        }
        for (int r = 0; r + 1 < kRings; ++r)
            for (std::uint32_t c = 0; c < 4; ++c) {
                const std::uint32_t a = 4 * r + c, b = 4 * r + (c + 1) % 4;
                indices.insert(indices.end(), {a, b, b + 4, a, b + 4, a + 4});
            }
        const std::uint32_t last = 4 * (kRings - 1);
        indices.insert(indices.end(), {0, 2, 1, 0, 3, 2, last, last + 1, last + 2, last, last + 2, last + 3});
    }
    std::uint32_t vertex_count() const { return std::uint32_t(bind.size() / 3); }

    MeshSkin skin() const { return MeshSkin{kJoints, joints.data(), weights.data()}; }
    MeshDesc desc(const MeshSkin* skin) const {
        MeshDesc d;
        d.positions = bind.data();
        d.vertex_count = vertex_count();
        d.indices = indices.data();
        d.index_count = std::uint32_t(indices.size());
        d.deforming = true;
        d.skin = skin;
        return d;
    }

    /// The palette bending the right half by `angle` rad about z at x = 2, the whole bar shifted by `shift`.
    static std::vector<glm::mat4> palette(float angle, glm::vec3 shift = glm::vec3(0.0f)) {
        const glm::mat4 move = glm::translate(glm::mat4(1.0f), shift);
        const glm::mat4 bend = glm::translate(glm::mat4(1.0f), glm::vec3(2.0f, 0.0f, 0.0f)) *
                               glm::rotate(glm::mat4(1.0f), angle, glm::vec3(0.0f, 0.0f, 1.0f)) *
                               glm::translate(glm::mat4(1.0f), glm::vec3(-2.0f, 0.0f, 0.0f));
        return {move, move * bend, move};
    }

    /// The pose on the CPU, through the same per-vertex blend as the skinning shader.
    std::vector<float> pose(const std::vector<glm::mat4>& palette) const {
        std::vector<float> out(bind.size());
        for (std::uint32_t v = 0; v < vertex_count(); ++v) {
            const std::uint16_t* j = &joints[4 * v];
            const glm::vec4 w(weights[4 * v], weights[4 * v + 1], weights[4 * v + 2], weights[4 * v + 3]);
            const glm::vec3 p =
                shaderio::skin_point(palette[j[0]], palette[j[1]], palette[j[2]], palette[j[3]], w,
                                     glm::vec3(bind[3 * v], bind[3 * v + 1], bind[3 * v + 2]));
            std::copy_n(&p.x, 3, &out[3 * v]);
        }
        return out;
    }
};

std::vector<Mat4> to_api(const std::vector<glm::mat4>& palette) {
    std::vector<Mat4> out;
    for (const glm::mat4& m : palette)
        out.push_back(to_api(m));
    return out;
}

std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> voxels_of(System& system) {
    std::size_t count = 0;
    EXPECT_TRUE(system.debug_voxels({}, count));
    std::vector<VoxelCoord> list(count);
    EXPECT_TRUE(system.debug_voxels(list, count));
    std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> out;
    for (const VoxelCoord& v : list)
        out.emplace_back(v.i, v.j, v.k);
    return out;
}

/// Points around the bar, where its motion shows in the wind.
std::vector<Vec3> probes() {
    std::vector<Vec3> out;
    for (float x = -3.5f; x <= 3.5f; x += 1.0f)
        for (float y = 1.5f; y <= 6.5f; y += 1.0f)
            for (float z = -1.5f; z <= 1.5f; z += 1.0f)
                out.push_back({x, y, z});
    return out;
}

/// Two Systems on the same small domain, each with the bar: `vertices` gets CPU-posed vertices, `bones`
/// the palette.
class Skinning : public ::testing::Test {
  protected:
    void SetUp() override {
        for (auto [system, watch] :
             {std::pair{&vertices_, &watch_vertices_}, std::pair{&bones_, &watch_bones_}}) {
            const Outcome created = System::create(small_desc(*watch), *system);
            ASSERT_TRUE(created) << created.message();
        }
        ASSERT_TRUE(vertices_->create_mesh(bar_.desc(nullptr), vertex_mesh_));
        const MeshSkin skin = bar_.skin();
        const Outcome made = bones_->create_mesh(bar_.desc(&skin), bone_mesh_);
        ASSERT_TRUE(made) << made.message();
        InstanceId instance = 0;
        ASSERT_TRUE(vertices_->create_instance(vertex_mesh_, place_, false, instance));
        ASSERT_TRUE(bones_->create_instance(bone_mesh_, place_, false, instance));
    }
    void TearDown() override {
        vertices_.reset();
        bones_.reset();
        for (const Watch* watch : {&watch_vertices_, &watch_bones_}) {
            EXPECT_EQ(watch->errors, 0) << watch->last;
            EXPECT_EQ(watch->live, 0) << "host allocations not freed";
        }
    }

    /// Poses both Systems with `palette` (one as vertices, one as bones) and steps them.
    void pose_and_step(const std::vector<glm::mat4>& palette, bool teleport, float dt = 0.05f) {
        const std::vector<float> posed = bar_.pose(palette);
        ASSERT_TRUE(vertices_->set_vertices(vertex_mesh_, posed.data(), bar_.vertex_count(), 12, teleport));
        const std::vector<Mat4> bones = to_api(palette);
        const Outcome set = bones_->set_bones(bone_mesh_, bones.data(), Bar::kJoints, teleport);
        ASSERT_TRUE(set) << set.message();
        for (System* system : {vertices_.get(), bones_.get()}) {
            const Outcome stepped = system->step(dt);
            ASSERT_TRUE(stepped) << stepped.message();
        }
    }

    /// The wind at the probes in both Systems; expects them equal and returns the fastest.
    float same_wind() {
        const std::vector<Vec3> points = probes();
        std::vector<Vec3> a(points.size()), b(points.size());
        EXPECT_TRUE(vertices_->query(points, a));
        EXPECT_TRUE(bones_->query(points, b));
        float fastest = 0.0f, differs = 0.0f;
        for (std::size_t i = 0; i < points.size(); ++i) {
            fastest = std::max(fastest, std::hypot(a[i].x, a[i].y, a[i].z));
            differs = std::max(differs, std::hypot(a[i].x - b[i].x, a[i].y - b[i].y, a[i].z - b[i].z));
        }
        EXPECT_LE(differs, 1e-4f * std::max(fastest, 1.0f)) << "the wind of the two paths differs";
        return fastest;
    }

    Bar bar_;
    Mat4 place_ = to_api(glm::translate(glm::mat4(1.0f), glm::vec3(-2.13f, 3.27f, 0.08f)));
    Watch watch_vertices_, watch_bones_;
    std::unique_ptr<System> vertices_, bones_;
    MeshId vertex_mesh_ = 0, bone_mesh_ = 0;
};

TEST_F(Skinning, bonesPoseTheMeshVoxelForVoxelAsCpuPosedVerticesFrameAfterFrame) {
    ASSERT_TRUE(bones_->set_ambient({1.0f, 0.0f, 0.0f}));
    ASSERT_TRUE(vertices_->set_ambient({1.0f, 0.0f, 0.0f}));
    std::vector<std::tuple<std::uint32_t, std::uint32_t, std::uint32_t>> first;
    for (int frame = 0; frame < 6; ++frame) {
        SCOPED_TRACE(frame);
        pose_and_step(Bar::palette(0.25f * float(frame)), false);
        const auto expected = voxels_of(*vertices_);
        ASSERT_FALSE(expected.empty());
        EXPECT_EQ(voxels_of(*bones_), expected);
        if (frame == 0) first = expected;
        // The bending bar's surface moves and pushes the air, the same on both paths.
        const float fastest = same_wind();
        if (frame > 0) {
            EXPECT_GT(fastest, 1.5f) << "the bending bar pushes the air";
        }
    }
    EXPECT_NE(voxels_of(*bones_), first) << "the bend moved the voxels";
    for (System* system : {vertices_.get(), bones_.get()})
        EXPECT_EQ(system->stats().rejected_triangles, 0u);
}

// A teleported pose moves the solid without pushing air, as set_vertices' teleport does; the same jump
// unflagged pushes it, on both paths alike.
TEST_F(Skinning, aTeleportedPoseFromBonesPushesNoAirAndAnUnflaggedJumpDoes) {
    for (int frame = 0; frame < 3; ++frame)
        pose_and_step(Bar::palette(0.0f), false);
    pose_and_step(Bar::palette(0.0f, {0.0f, 0.0f, 1.5f}), true);
    EXPECT_EQ(voxels_of(*bones_), voxels_of(*vertices_));
    EXPECT_LT(same_wind(), 1e-3f) << "a teleport pushes no air";
    pose_and_step(Bar::palette(0.0f), false);
    EXPECT_EQ(voxels_of(*bones_), voxels_of(*vertices_));
    EXPECT_GT(same_wind(), 5.0f) << "the jump back, unflagged, pushes the air";
}

// The last of set_vertices and set_bones before a step sets its pose.
TEST_F(Skinning, theLastOfSetVerticesAndSetBonesBeforeAStepSetsThePose) {
    const std::vector<glm::mat4> straight = Bar::palette(0.0f), bent = Bar::palette(1.0f);
    const std::vector<float> straight_vertices = bar_.pose(straight), bent_vertices = bar_.pose(bent);
    const std::vector<Mat4> straight_bones = to_api(straight), bent_bones = to_api(bent);
    ASSERT_TRUE(vertices_->set_vertices(vertex_mesh_, bent_vertices.data(), bar_.vertex_count()));
    ASSERT_TRUE(vertices_->step(0.05f));
    ASSERT_TRUE(bones_->set_bones(bone_mesh_, bent_bones.data(), Bar::kJoints));
    ASSERT_TRUE(bones_->set_vertices(bone_mesh_, straight_vertices.data(), bar_.vertex_count()));
    ASSERT_TRUE(bones_->set_bones(bone_mesh_, bent_bones.data(), Bar::kJoints));
    ASSERT_TRUE(bones_->step(0.05f));
    EXPECT_EQ(voxels_of(*bones_), voxels_of(*vertices_)) << "bones after vertices";
    ASSERT_TRUE(vertices_->set_vertices(vertex_mesh_, straight_vertices.data(), bar_.vertex_count()));
    ASSERT_TRUE(vertices_->step(0.05f));
    ASSERT_TRUE(bones_->set_bones(bone_mesh_, bent_bones.data(), Bar::kJoints));
    ASSERT_TRUE(bones_->set_vertices(bone_mesh_, straight_vertices.data(), bar_.vertex_count()));
    ASSERT_TRUE(bones_->step(0.05f));
    EXPECT_EQ(voxels_of(*bones_), voxels_of(*vertices_)) << "vertices after bones";
}

// The sample's characters, walking: CPU-posed by AnimatedMesh::pose on one System, skinned on the GPU from
// AnimatedMesh::bone_palette on the other, on a grid of 12.5 cm voxels.
TEST(SkinningCharacters, theFoxAndCesiumManFromBonesMatchTheirCpuPosesVoxelForVoxel) {
    struct Character {
        gust::AnimatedMesh animation;
        AnimatedMesh::BoneSkin skin;
        glm::mat4 place;
        MeshId mesh[2] = {0, 0};
    };
    std::vector<Character> characters;
    for (const auto& [file, place] :
         {std::pair{"characters/CesiumMan.glb",
                    glm::translate(glm::mat4(1.0f), glm::vec3(-0.9f, 0.01f, 0.1f))},
          std::pair{"characters/Fox.glb",
                    glm::scale(glm::translate(glm::mat4(1.0f), glm::vec3(0.9f, 0.01f, -0.2f)),
                               glm::vec3(0.01f))}}) {
        Result<AnimatedMesh> loaded = AnimatedMesh::load(std::string(GUST_ASSETS_DIR) + "/" + file);
        ASSERT_TRUE(loaded.ok()) << loaded.message();
        Result<AnimatedMesh::BoneSkin> skin = loaded->bone_skin();
        ASSERT_TRUE(skin.ok()) << skin.message();
        characters.push_back({std::move(*loaded), std::move(*skin), place});
    }
    Watch watch[2];
    std::unique_ptr<System> systems[2]; // [0]: posed vertices, [1]: bones
    for (int s = 0; s < 2; ++s) {
        SystemDesc desc = small_desc(watch[s]);
        desc.domain.cell_size = 0.25f;
        desc.domain.focus = {0.0f, 1.0f, 0.0f};
        ASSERT_TRUE(System::create(desc, systems[s]));
        for (Character& c : characters) {
            const MeshSkin skin{c.skin.joint_count, c.skin.joints.data(), c.skin.weights.data()};
            MeshDesc mesh;
            mesh.positions = &c.skin.bind[0].x;
            mesh.vertex_count = std::uint32_t(c.skin.bind.size());
            mesh.indices = c.animation.rest_pose().indices.data();
            mesh.index_count = std::uint32_t(c.animation.rest_pose().indices.size());
            mesh.deforming = true;
            mesh.skin = s == 1 ? &skin : nullptr;
            ASSERT_TRUE(systems[s]->create_mesh(mesh, c.mesh[s]));
            InstanceId instance = 0;
            ASSERT_TRUE(systems[s]->create_instance(c.mesh[s], to_api(c.place), false, instance));
        }
    }
    for (int frame = 0; frame < 4; ++frame) {
        SCOPED_TRACE(frame);
        const double t = 0.3 * frame;
        for (Character& c : characters) {
            std::vector<glm::vec3> posed;
            c.animation.pose(0, t, true, posed);
            ASSERT_TRUE(systems[0]->set_vertices(c.mesh[0], &posed[0].x, std::uint32_t(posed.size())));
            std::vector<glm::mat4> palette;
            c.animation.bone_palette(0, t, true, palette);
            const std::vector<Mat4> bones = to_api(palette);
            ASSERT_TRUE(systems[1]->set_bones(c.mesh[1], bones.data(), std::uint32_t(bones.size())));
        }
        for (auto& system : systems)
            ASSERT_TRUE(system->step(0.05f));
        const auto expected = voxels_of(*systems[0]);
        EXPECT_GT(expected.size(), 200u) << "both characters are voxelized";
        EXPECT_EQ(voxels_of(*systems[1]), expected);
    }
    for (auto& system : systems)
        system.reset();
    for (const Watch& w : watch)
        EXPECT_EQ(w.errors, 0) << w.last;
}

TEST_F(Skinning, rejectsBadSkinsAndPalettesWithAClearErrorAndKeepsWorking) {
    System& system = *bones_;
    const auto refused = [](const Outcome& o, const char* says) {
        EXPECT_EQ(o.code(), ErrorCode::InvalidArgument) << says;
        EXPECT_NE(o.message().find(says), std::string::npos) << o.message();
    };
    // Skins: each fault alone, on a copy of the bar's.
    const auto create = [&](auto&& spoil) {
        Bar bar;
        MeshSkin skin = bar.skin();
        MeshDesc desc = bar.desc(&skin);
        spoil(bar, skin, desc);
        MeshId id = 7;
        const Outcome o = system.create_mesh(desc, id);
        EXPECT_EQ(id, 0u);
        return o;
    };
    refused(create([](Bar& bar, MeshSkin&, MeshDesc&) { bar.weights[9] = std::nanf(""); }), "weight");
    refused(create([](Bar& bar, MeshSkin&, MeshDesc&) { bar.weights[9] = -0.5f; }), "weight");
    refused(create([](Bar& bar, MeshSkin&, MeshDesc&) { bar.weights[8] = bar.weights[9] = 0.0f; }),
            "all weights are 0");
    refused(create([](Bar& bar, MeshSkin&, MeshDesc&) { bar.joints[13] = 3; }), "out of range");
    refused(create([](Bar&, MeshSkin& skin, MeshDesc&) { skin.joint_count = 0; }), "joint count");
    refused(create([](Bar&, MeshSkin& skin, MeshDesc&) { skin.weights = nullptr; }), "null");
    refused(create([](Bar&, MeshSkin&, MeshDesc& desc) { desc.deforming = false; }), "deforming");

    // Palettes.
    std::vector<Mat4> palette = to_api(Bar::palette(0.5f));
    refused(system.set_bones(bone_mesh_, palette.data(), 2), "3 joints");
    refused(system.set_bones(bone_mesh_, nullptr, Bar::kJoints), "null");
    palette[1].m[13] = std::numeric_limits<float>::infinity();
    refused(system.set_bones(bone_mesh_, palette.data(), Bar::kJoints), "finite");
    palette[1].m[13] = 0.0f;
    palette[2].m[3] = 0.5f;
    refused(system.set_bones(bone_mesh_, palette.data(), Bar::kJoints), "affine");
    palette[2].m[3] = 0.0f;
    // A deforming mesh without a skin, a static mesh, a dead handle.
    MeshId plain = 0, fixed = 0;
    const Box box(1.0f);
    ASSERT_TRUE(system.create_mesh(box.desc(true), plain));
    ASSERT_TRUE(system.create_mesh(box.desc(false), fixed));
    refused(system.set_bones(plain, palette.data(), Bar::kJoints), "no skin");
    refused(system.set_bones(fixed, palette.data(), Bar::kJoints), "deforming");
    EXPECT_EQ(system.set_bones(12345, palette.data(), Bar::kJoints).code(), ErrorCode::InvalidHandle);

    // Nothing refused reached the GPU: the System poses and steps as before, like the CPU-posed one.
    pose_and_step(Bar::palette(0.5f), false);
    EXPECT_EQ(voxels_of(*bones_), voxels_of(*vertices_));
}

} // namespace
} // namespace gust::test
