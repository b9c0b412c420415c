// Built with Assimp (and its dependency libdraco) ahead of gust_scene on the link line. libdraco
// exports its own tinygltf build under the same symbol names, so here the dynamic linker serves
// tinygltf calls from draco: glTF import must refuse with an explanation instead of corrupting memory.
#include "gust/scene/import.hpp"

#include <filesystem>
#include <gtest/gtest.h>
#include <string>

namespace {

const std::filesystem::path kAssets = GUST_ASSETS_DIR;

TEST(LinkOrder, refusesGltfWhenDracoServesTinygltfCalls) {
    const gust::Result<gust::Mesh> mesh = gust::load_mesh(kAssets / "characters/Fox.glb");
    ASSERT_FALSE(mesh.ok());
    EXPECT_NE(mesh.message().find("libdraco"), std::string::npos) << mesh.message();
    EXPECT_NE(mesh.message().find("link TinyGLTF::TinyGLTF before assimp::assimp"), std::string::npos)
        << mesh.message();
}

TEST(LinkOrder, stillLoadsFormatsReadByAssimp) {
    const gust::Result<gust::Mesh> mesh = gust::load_mesh(kAssets / "scans/bunny.ply");
    ASSERT_TRUE(mesh.ok()) << mesh.message();
    EXPECT_EQ(mesh->triangle_count(), 3674u);
}

} // namespace
