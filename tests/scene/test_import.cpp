// Mesh import: real assets with known counts and bounds, every glTF primitive mode, synthetic glTF
// files for transforms and accessors, and broken files that must fail with a clear message.
#include "gust/scene/import.hpp"
#include "gust/scene/primitives.hpp"
#include "scene_test_support.hpp"

#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;
using gust::test::GltfWriter;
using gust::test::kTriangle;
using gust::test::triangle_primitive;
using nlohmann::json;

const fs::path kAssets = GUST_ASSETS_DIR;
const fs::path kModels = GUST_ASSIMP_MODELS_DIR;

struct Box {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{std::numeric_limits<float>::lowest()};
};

Box bounds(const gust::Mesh& mesh) {
    Box box;
    for (const glm::vec3& p : mesh.positions) {
        box.min = glm::min(box.min, p);
        box.max = glm::max(box.max, p);
    }
    return box;
}

glm::dvec3 corner(const gust::Mesh& mesh, std::size_t triangle, int k) {
    return glm::dvec3(mesh.positions[mesh.indices[3 * triangle + static_cast<std::size_t>(k)]]);
}

glm::dvec3 area_vector(const gust::Mesh& mesh, std::size_t triangle) {
    const glm::dvec3 a = corner(mesh, triangle, 0);
    return 0.5 * glm::cross(corner(mesh, triangle, 1) - a, corner(mesh, triangle, 2) - a);
}

double total_area(const gust::Mesh& mesh) {
    double area = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
        area += glm::length(area_vector(mesh, t));
    return area;
}

// Positive for a closed mesh wound counter-clockwise seen from outside.
double signed_volume(const gust::Mesh& mesh) {
    double volume = 0;
    for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
        volume += glm::dot(corner(mesh, t, 0), glm::cross(corner(mesh, t, 1), corner(mesh, t, 2))) / 6.0;
    }
    return volume;
}

void expect_near(glm::vec3 actual, glm::vec3 expected, float tolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

void expect_bounds(const gust::Mesh& mesh, glm::vec3 min, glm::vec3 max, float tolerance) {
    const Box box = bounds(mesh);
    expect_near(box.min, min, tolerance);
    expect_near(box.max, max, tolerance);
}

// A test name from a relative file path: "glTF2/draco/2CylinderEngine.gltf" ->
// "glTF2_draco_2CylinderEngine_gltf".
std::string test_name(std::string path) {
    for (char& c : path) {
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    }
    return path;
}

// Loads a file that must load; the failure message is shown otherwise.
gust::Mesh load_ok(const fs::path& path) {
    gust::Result<gust::Mesh> mesh = gust::load_mesh(path);
    EXPECT_TRUE(mesh.ok()) << mesh.message();
    if (!mesh.ok()) return {};
    EXPECT_TRUE(gust::validate_mesh(*mesh).ok());
    return *mesh;
}

// Loads a file that must fail, and checks that the message names the file and gives the reason.
void expect_failure(const fs::path& path, const std::string& reason) {
    gust::Result<gust::Mesh> mesh = gust::load_mesh(path);
    ASSERT_FALSE(mesh.ok()) << path << " loaded with " << mesh->triangle_count() << " triangles";
    EXPECT_EQ(mesh.message().rfind(path.string() + ": ", 0), 0u)
        << "starts with the path: " << mesh.message();
    EXPECT_NE(mesh.message().find(reason), std::string::npos)
        << "says '" << reason << "': " << mesh.message();
}

// A fresh directory per test for files written by the test.
class ImportTest : public testing::Test {
  protected:
    void SetUp() override {
        static std::atomic<int> counter{0};
        dir_ = fs::temp_directory_path() /
               ("gust_scene_tests_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    fs::path write(const std::string& name, const std::string& contents) const {
        const fs::path path = dir_ / name;
        std::ofstream(path, std::ios::binary) << contents;
        return path;
    }

    fs::path dir_;
};

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// ---------------------------------------------------------------------------------------------------
// Real assets

TEST(LoadMesh, loadsBunnyPly) {
    const gust::Mesh mesh = load_ok(kAssets / "scans/bunny.ply");
    EXPECT_EQ(mesh.name, "bunny.ply");
    EXPECT_EQ(mesh.positions.size(), 1839u);
    EXPECT_EQ(mesh.triangle_count(), 3674u);
    expect_bounds(mesh, {-4.95848f, -0.00315f, -3.72983f}, {4.94885f, 9.65475f, 3.81064f}, 1e-4f);
    EXPECT_GT(signed_volume(mesh), 0.0) << "closed and wound outward";
}

TEST(LoadMesh, loadsDragonRes3Ply) {
    const gust::Mesh mesh = load_ok(kAssets / "scans/dragon_res3.ply");
    EXPECT_EQ(mesh.triangle_count(), 47794u);
    // Identical positions are merged, so at most the file's 22,998 vertices remain.
    EXPECT_LE(mesh.positions.size(), 22998u);
    EXPECT_GT(mesh.positions.size(), 22900u);
    expect_bounds(mesh, {-0.10767f, 0.05277f, -0.05005f}, {0.09598f, 0.19664f, 0.04083f}, 1e-5f);
}

TEST(LoadMesh, loadsDragonFullGlbWithUnsignedIntIndices) {
    const gust::Mesh mesh = load_ok(kAssets / "scans/dragon_full.glb");
    EXPECT_EQ(mesh.positions.size(), 437645u);
    EXPECT_EQ(mesh.triangle_count(), 871414u);
    expect_bounds(mesh, {-0.10832f, 0.05273f, -0.05041f}, {0.09657f, 0.19717f, 0.04121f}, 1e-5f);
}

TEST(LoadMesh, loadsFoxGlbInBindPose) {
    const gust::Mesh mesh = load_ok(kAssets / "characters/Fox.glb");
    EXPECT_EQ(mesh.triangle_count(), 576u);
    expect_bounds(mesh, {-12.59272f, -0.12174f, -88.095f}, {12.59272f, 78.90719f, 66.62486f}, 1e-3f);
}

TEST(LoadMesh, loadsCesiumManGlbStandingInItsRestPose) {
    const gust::Mesh mesh = load_ok(kAssets / "characters/CesiumMan.glb");
    EXPECT_EQ(mesh.triangle_count(), 4672u);
    // The raw POSITION data spans x [-0.131, 0.181], y [-0.569, 0.569], z [0, 1.507] (Z-up). The joints
    // hang under the file's Z_UP node, (x, y, z) -> (x, z, -y), and its Armature node,
    // (x, y, z) -> (y, -x, z), and its inverse bind matrices undo only the joints' own placement, so at
    // rest the figure stands as every glTF viewer shows it: both turns applied to the raw box.
    expect_bounds(mesh, {-0.56914f, 0.0f, -0.131f}, {0.56914f, 1.50655f, 0.18095f}, 1e-3f);
}

TEST(LoadMesh, loadsPalmTreeGltfWithExternalBin) {
    const gust::Mesh mesh = load_ok(kAssets / "foliage/PalmTree/PalmTree.gltf");
    EXPECT_EQ(mesh.triangle_count(), 10124u);
    expect_bounds(mesh, {-196.01877f, -1.02828f, -196.01877f}, {196.01877f, 3.82726f, 196.01877f}, 1e-3f);
}

struct Documented {
    const char* file;
    std::size_t triangles;
    glm::vec3 min;
    glm::vec3 max;
};

class LoadsDocumentedAsset : public testing::TestWithParam<Documented> {};

TEST_P(LoadsDocumentedAsset, withCountAndBoundsFromTheAssetReadme) {
    const gust::Mesh mesh = load_ok(kAssets / GetParam().file);
    EXPECT_EQ(mesh.triangle_count(), GetParam().triangles);
    expect_bounds(mesh, GetParam().min, GetParam().max, 1e-4f);
}

INSTANTIATE_TEST_SUITE_P(
    Assets, LoadsDocumentedAsset,
    testing::Values(
        Documented{"foliage/grass.glb", 72, {-0.25549f, 0.0f, -0.26778f}, {0.25549f, 0.30926f, 0.26778f}},
        Documented{"foliage/grass-trees-tall.glb", 472, {-0.5f, 0.0f, -0.5f}, {0.57193f, 0.75964f, 0.50616f}},
        Documented{
            "foliage/tree_detailed.glb", 402, {-0.43248f, -0.05f, -0.37214f}, {0.41463f, 1.28242f, 0.38947f}},
        Documented{"architecture/building-small-a.glb", 452, {-0.5f, 0.0f, -0.5f}, {0.5f, 0.95f, 0.5f}},
        Documented{"architecture/building-small-c.glb", 834, {-0.5f, 0.0f, -0.5f}, {0.5f, 1.75f, 0.5f}},
        Documented{"architecture/building-garage.glb", 196, {-0.5f, 0.0f, -0.5f}, {0.5f, 0.55f, 0.5f}}),
    [](const testing::TestParamInfo<Documented>& p) { return test_name(p.param.file); });

// ---------------------------------------------------------------------------------------------------
// assimp-testmodels: valid files

TEST(LoadMesh, loadsObjFiles) {
    EXPECT_EQ(load_ok(kModels / "OBJ/spider.obj").triangle_count(), 1368u);
    EXPECT_EQ(load_ok(kModels / "OBJ/WusonOBJ.obj").triangle_count(), 3732u);
}

TEST(LoadMesh, triangulatesObjPolygons) {
    // Six quads, one per face of a unit cube.
    const gust::Mesh mesh = load_ok(kModels / "OBJ/box_without_lineending.obj");
    EXPECT_EQ(mesh.triangle_count(), 12u);
    EXPECT_EQ(mesh.positions.size(), 8u);
}

TEST(LoadMesh, loadsBinaryAndAsciiStlAlike) {
    const gust::Mesh binary = load_ok(kModels / "STL/Spider_binary.stl");
    const gust::Mesh ascii = load_ok(kModels / "STL/Spider_ascii.stl");
    EXPECT_EQ(binary.triangle_count(), 1368u);
    EXPECT_EQ(ascii.triangle_count(), 1368u);
    const Box a = bounds(binary);
    const Box b = bounds(ascii);
    expect_near(a.min, b.min, 1e-4f);
    expect_near(a.max, b.max, 1e-4f);
}

TEST(LoadMesh, loadsEverySolidOfAnAsciiStl) {
    EXPECT_EQ(load_ok(kModels / "STL/triangle_with_two_solids.stl").triangle_count(), 2u);
}

TEST(LoadMesh, loadsOpenStlSurface) {
    EXPECT_EQ(load_ok(kModels / "STL/sphereWithHole.stl").triangle_count(), 285u);
}

TEST(LoadMesh, loadsAsciiAndBinaryPlyCubes) {
    for (const char* file : {"PLY/cube.ply", "PLY/cube_binary.ply"}) {
        const gust::Mesh mesh = load_ok(kModels / file);
        EXPECT_EQ(mesh.triangle_count(), 12u) << file;
        EXPECT_EQ(mesh.positions.size(), 8u) << file;
    }
}

TEST(LoadMesh, appliesNodeTransformsAndInstancingOf2CylinderEngine) {
    // 75,730 triangles in its meshes; several meshes are placed by more than one node.
    const gust::Mesh mesh = load_ok(kModels / "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    EXPECT_EQ(mesh.triangle_count(), 121496u);
}

TEST(LoadMesh, loadsTheSameBoxFromGlbExternalBinAndDataUri) {
    const gust::Mesh glb = load_ok(kModels / "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    const gust::Mesh external = load_ok(kModels / "glTF2/BoxTextured-glTF/BoxTextured.gltf");
    const gust::Mesh embedded = load_ok(kModels / "glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf");
    EXPECT_EQ(glb.triangle_count(), 12u);
    EXPECT_EQ(glb.positions, external.positions);
    EXPECT_EQ(glb.positions, embedded.positions);
    EXPECT_EQ(glb.indices, external.indices);
    EXPECT_EQ(glb.indices, embedded.indices);
    EXPECT_NEAR(total_area(glb), 6.0, 1e-5) << "unit cube";
}

TEST(LoadMesh, loadsSkinnedMeshInItsRestPose) {
    // Raw positions span (0, 0, 0)-(1, 2, 0). The joints sit at (0, 1, 0) at rest and their inverse
    // bind matrices take off (0.5, 1, 0), so skinning at rest moves the figure by -0.5 along x.
    const gust::Mesh mesh = load_ok(kModels / "glTF2/simple_skin/simple_skin.gltf");
    EXPECT_EQ(mesh.triangle_count(), 8u);
    expect_bounds(mesh, {-0.5f, 0, 0}, {0.5f, 2, 0}, 1e-6f);
}

TEST(LoadMesh, keepsNonFinitePositionsOfBoxWithInfinites) {
    const gust::Mesh mesh = load_ok(kModels / "glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb");
    EXPECT_GT(mesh.triangle_count(), 0u);
    std::size_t infinite = 0;
    for (const glm::vec3& p : mesh.positions)
        infinite += (std::isinf(p.x) || std::isinf(p.y) || std::isinf(p.z));
    EXPECT_GT(infinite, 0u);
}

// ---------------------------------------------------------------------------------------------------
// glTF primitive modes (glTF-Asset-Generator Mesh_PrimitiveMode_00..15)

fs::path primitive_mode_file(int n) {
    return kModels / "glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode" /
           ("Mesh_PrimitiveMode_" + std::string(n < 10 ? "0" : "") + std::to_string(n) + ".gltf");
}

class PrimitiveMode : public testing::TestWithParam<int> {};

TEST_P(PrimitiveMode, pointsAndLinesFailAsNoTriangles) {
    expect_failure(primitive_mode_file(GetParam()), "no triangles (only points or lines)");
}

std::string mode_name(const testing::TestParamInfo<int>& info) {
    return "Mesh_PrimitiveMode_" + std::to_string(info.param);
}

INSTANTIATE_TEST_SUITE_P(PointsAndLines, PrimitiveMode, testing::Values(0, 1, 2, 3, 7, 8, 9, 10), mode_name);

class TriangleMode : public testing::TestWithParam<int> {};

TEST_P(TriangleMode, expandsToTheSameTwoTrianglesAsTheTriangleListFile) {
    // File 06 is the plain non-indexed triangle list of the same quad.
    const gust::Mesh reference = load_ok(primitive_mode_file(6));
    const gust::Mesh mesh = load_ok(primitive_mode_file(GetParam()));
    ASSERT_EQ(reference.triangle_count(), 2u);
    ASSERT_EQ(mesh.triangle_count(), 2u);
    EXPECT_NEAR(total_area(mesh), total_area(reference), 1e-6);
    const glm::dvec3 facing = area_vector(reference, 0);
    for (std::size_t t = 0; t < 2; ++t) {
        EXPECT_GT(glm::dot(area_vector(mesh, t), facing), 0.0) << "triangle " << t << " is wound backwards";
    }
    expect_bounds(mesh, bounds(reference).min, bounds(reference).max, 1e-6f);
}

// 04/11 strips, 05/12 fans, 13/14/15 triangle lists with uint32, uint8 and uint16 indices.
INSTANTIATE_TEST_SUITE_P(StripsFansAndIndexTypes, TriangleMode, testing::Values(4, 5, 11, 12, 13, 14, 15),
                         mode_name);

// ---------------------------------------------------------------------------------------------------
// assimp-testmodels: broken files

struct Broken {
    const char* file;
    const char* reason;
};

class RejectsBrokenFile : public testing::TestWithParam<Broken> {};

TEST_P(RejectsBrokenFile, withFileNameAndReason) {
    expect_failure(kModels / GetParam().file, GetParam().reason);
}

INSTANTIATE_TEST_SUITE_P(
    AssimpTestModels, RejectsBrokenFile,
    testing::Values(
        Broken{"glTF2/IndexOutOfRange/IndexOutOfRange.gltf",
               "out of range (24 vertices) in mesh 'Mesh' primitive 0"},
        Broken{"glTF2/IndexOutOfRange/AllIndicesOutOfRange.gltf", "out of range (24 vertices)"},
        Broken{"glTF2/IncorrectVertexArrays/Cube.gltf",
               "vertex count 35 is not a multiple of 3 in mesh 'TruncatedCube' primitive 0"},
        Broken{"glTF2/RecursiveNodes/RecursiveNodes.gltf", "node cycle at node 0"},
        Broken{"glTF2/MissingBin/BoxTextured.gltf", "BoxTextured0.bin"},
        Broken{"glTF2/TestNoRootNode/NoScene.gltf", "scene 0 does not exist"},
        Broken{"glTF2/TestNoRootNode/SceneWithoutNodes.gltf", "no triangles"},
        Broken{"glTF2/SchemaFailures/sceneWrongType.gltf",
               "/scene must be a non-negative integer (found string)"},
        Broken{"glTF2/wrongTypes/badArray.gltf", "/meshes/0/primitives must be an array"},
        Broken{"glTF2/wrongTypes/badExtension.gltf", "/extensions/KHR_texture_transform must be an object"},
        Broken{"glTF2/wrongTypes/badNumber.gltf", "/normalTexture/scale must be a number"},
        Broken{"glTF2/wrongTypes/badObject.gltf", "/materials/0/pbrMetallicRoughness must be an object"},
        Broken{"glTF2/wrongTypes/badString.gltf", "/scenes/0/name must be a string"},
        Broken{"glTF2/wrongTypes/badUint.gltf", "/index must be a non-negative integer"},
        Broken{"glTF2/draco/2CylinderEngine.gltf",
               "required extension KHR_draco_mesh_compression is not supported"},
        Broken{"glTF/BoxTextured-glTF/BoxTextured.gltf", "glTF 1.0 is not supported"},
        Broken{"invalid/empty.ply", "empty file"}, Broken{"invalid/empty.obj", "empty file"},
        Broken{"invalid/malformed.obj", "face index"},
        Broken{"invalid/OutOfMemory.off",
               "unsupported extension '.off' (expected .ply, .obj, .stl, .gltf, .glb)"},
        Broken{"PLY/points.ply", "no triangles (only points or lines)"},
        Broken{"OBJ/point_cloud.obj", "no triangles (only points or lines)"},
        Broken{"OBJ/testline.obj", "no triangles (only points or lines)"},
        Broken{"OBJ/testpoints.obj", "no triangles (only points or lines)"}),
    [](const testing::TestParamInfo<Broken>& p) { return test_name(p.param.file); });

// ---------------------------------------------------------------------------------------------------
// Paths

TEST_F(ImportTest, rejectsMissingFile) {
    expect_failure(dir_ / "nothing_here.ply", "file not found");
}

TEST_F(ImportTest, rejectsDirectory) {
    fs::create_directory(dir_ / "folder.obj");
    expect_failure(dir_ / "folder.obj", "is a directory");
}

TEST_F(ImportTest, rejectsAGltfBufferThatNamesAFolder) {
    // tinygltf read the folder's size as 2^63 and failed on the allocation ("std::bad_alloc").
    fs::create_directory(dir_ / "data.bin");
    expect_failure(
        write("folder_buffer.gltf",
              R"({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "data.bin"}]})"),
        "data.bin is a directory, not a file");
}

TEST_F(ImportTest, rejectsUnknownExtension) {
    expect_failure(write("mesh.abc", "anything"),
                   "unsupported extension '.abc' (expected .ply, .obj, .stl, .gltf, .glb)");
}

TEST_F(ImportTest, rejectsFileWithoutExtension) {
    expect_failure(write("mesh", "anything"), "no file extension");
}

TEST_F(ImportTest, acceptsUpperCaseExtension) {
    const fs::path path = write("CUBE.PLY", read_file(kModels / "PLY/cube.ply"));
    EXPECT_EQ(load_ok(path).triangle_count(), 12u);
}

// A NaN corner is its own vertex: welding it into a finite corner would turn its triangle into a finite,
// zero-area one, which the voxelizer skips instead of counting as rejected.
TEST_F(ImportTest, keepsANanCornerOfAnAsciiPlyApartFromTheFiniteOnes) {
    const fs::path path = write("nan.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                           "property float y\nproperty float z\nelement face 1\n"
                                           "property list uchar int vertex_indices\nend_header\n"
                                           "0 0 0\n1 0 0\nnan 1 0\n3 0 1 2\n");
    const gust::Mesh mesh = load_ok(path);
    ASSERT_EQ(mesh.triangle_count(), 1u);
    ASSERT_EQ(mesh.positions.size(), 3u);
    const glm::vec3 corner = mesh.positions[mesh.indices[2]];
    EXPECT_TRUE(std::isnan(corner.x));
    EXPECT_NE(mesh.indices[2], mesh.indices[0]);
    EXPECT_NE(mesh.indices[2], mesh.indices[1]);
}

TEST(LoadMesh, weldsTheCornersAnStlListsPerTriangle) {
    // An STL lists three corners per triangle; the closed spider shares each corner among its triangles.
    const gust::Mesh mesh = load_ok(kModels / "STL/Spider_binary.stl");
    EXPECT_LT(mesh.positions.size(), 3 * mesh.triangle_count() / 4);
}

// ---------------------------------------------------------------------------------------------------
// PLY and STL headers that would make Assimp allocate from unchecked counts

const std::string kPlyTriangleHeader = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                       "property float y\nproperty float z\n";

TEST_F(ImportTest, rejectsAsciiPlyDeclaringMoreFacesThanTheFileHolds) {
    const fs::path path =
        write("huge.ply", kPlyTriangleHeader + "element face 353535235358\n"
                                               "property list uchar int vertex_indices\nend_header\n"
                                               "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    expect_failure(path, "header declares 353535235358 'face' items");
}

TEST_F(ImportTest, rejectsBinaryPlyDeclaringMoreVerticesThanTheFileHolds) {
    const std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 353535235358\n"
                               "property float x\nproperty float y\nproperty float z\nend_header\n";
    expect_failure(write("huge.ply", header + std::string(1000, '\0')),
                   "header declares 353535235358 'vertex'");
}

TEST_F(ImportTest, rejectsBinaryPlyWithHugeListLength) {
    std::string body = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nelement face 1\n"
                       "property list int int vertex_indices\nend_header\n";
    body += std::string(36, '\0');
    const std::int32_t length = 2000000000;
    body.append(reinterpret_cast<const char*>(&length), sizeof length);
    body += std::string(12, '\0');
    expect_failure(write("list.ply", body), "file truncated");
}

TEST_F(ImportTest, rejectsTruncatedBinaryPly) {
    const std::string bunny = read_file(kAssets / "scans/bunny.ply");
    expect_failure(write("bunny.ply", bunny.substr(0, bunny.size() / 2)), "file truncated");
}

TEST_F(ImportTest, rejectsPlyWithoutMagic) {
    expect_failure(write("fake.ply", "not a ply file\n"), "not a PLY file");
}

TEST_F(ImportTest, rejectsPlyFaceIndexOutOfRange) {
    const fs::path path =
        write("index.ply", kPlyTriangleHeader + "element face 1\nproperty list uchar int vertex_indices\n"
                                                "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99\n");
    expect_failure(path, "out of range");
}

TEST_F(ImportTest, rejectsBinaryStlDeclaringMoreTrianglesThanTheFileHolds) {
    std::string body(80, ' ');
    const std::uint32_t count = 1000000000;
    body.append(reinterpret_cast<const char*>(&count), sizeof count);
    body += std::string(100, '\0');
    expect_failure(write("huge.stl", body), "binary STL header declares 1000000000 triangles");
}

TEST_F(ImportTest, keepsParserMessagesToOneShortLine) {
    // Assimp quotes the rest of the file when a number does not parse.
    std::string stl = "solid x\nfacet normal 0 0 1\nouter loop\nvertex ~0 0 0\n";
    for (int i = 0; i < 2000; ++i)
        stl += "vertex 1 0 0\n";
    const gust::Result<gust::Mesh> mesh =
        gust::load_mesh(write("long.stl", stl + "endloop\nendfacet\nendsolid x\n"));
    ASSERT_FALSE(mesh.ok());
    EXPECT_NE(mesh.message().find("cannot parse"), std::string::npos) << mesh.message();
    EXPECT_LT(mesh.message().size(), 500u);
    EXPECT_EQ(mesh.message().find('\n'), std::string::npos);
}

// ---------------------------------------------------------------------------------------------------
// glTF: transforms, accessors and structure (synthetic files)

TEST_F(ImportTest, appliesTrsAndMatrixTransformsDownTheHierarchy) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    // Child: matrix translating by (0,0,5). Parent: translate (10,0,0), rotate 90 degrees about +z, scale 2.
    const json child_matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 5, 1};
    const int child = gltf.add_node({{"mesh", mesh}, {"matrix", child_matrix}});
    const double s = std::sqrt(0.5);
    const int parent = gltf.add_node({{"children", {child}},
                                      {"translation", {10, 0, 0}},
                                      {"rotation", {0, 0, s, s}},
                                      {"scale", {2, 2, 2}}});
    gltf.add_root(parent);
    const gust::Mesh loaded = load_ok(write("trs.gltf", gltf.text()));
    ASSERT_EQ(loaded.positions.size(), 3u);
    // p -> T * R * S * (p + (0,0,5)); R maps x to y and y to -x.
    expect_near(loaded.positions[0], {10, 0, 10}, 1e-5f);
    expect_near(loaded.positions[1], {10, 2, 10}, 1e-5f);
    expect_near(loaded.positions[2], {8, 0, 10}, 1e-5f);
}

TEST_F(ImportTest, instancesAMeshOncePerNode) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    gltf.add_root(gltf.add_node({{"mesh", mesh}}));
    gltf.add_root(gltf.add_node({{"mesh", mesh}, {"translation", {0, 0, 3}}}));
    const gust::Mesh loaded = load_ok(write("instances.gltf", gltf.text()));
    EXPECT_EQ(loaded.triangle_count(), 2u);
    expect_bounds(loaded, {0, 0, 0}, {1, 1, 3}, 0.0f);
}

TEST_F(ImportTest, ignoresTheNodeTransformOfASkinnedMesh) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    const int joint = gltf.add_node({{"translation", {0, 7, 0}}});
    gltf.doc()["skins"] = json::array({{{"joints", {joint}}}});
    gltf.add_root(
        gltf.add_node({{"mesh", mesh}, {"skin", 0}, {"translation", {5, 5, 5}}, {"scale", {3, 3, 3}}}));
    gltf.add_root(joint);
    const gust::Mesh loaded = load_ok(write("skinned.gltf", gltf.text()));
    EXPECT_EQ(loaded.positions, kTriangle);
}

TEST_F(ImportTest, storesPositionsSharedByPrimitivesOnce) {
    GltfWriter gltf;
    const std::vector<glm::vec3> quad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const int positions = gltf.add_positions(quad);
    const int first = gltf.add_indices({0, 1, 2});
    const int second = gltf.add_indices({0, 2, 3});
    const int mesh =
        gltf.add_mesh(json::array({{{"attributes", {{"POSITION", positions}}}, {"indices", first}},
                                   {{"attributes", {{"POSITION", positions}}}, {"indices", second}}}));
    gltf.add_root(gltf.add_node({{"mesh", mesh}}));
    const gust::Mesh loaded = load_ok(write("shared.gltf", gltf.text()));
    EXPECT_EQ(loaded.positions, quad);
    EXPECT_EQ(loaded.indices, (std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3}));
}

TEST_F(ImportTest, appliesSparseAccessorValues) {
    GltfWriter gltf;
    const int base = gltf.add_view(kTriangle.data(), kTriangle.size() * sizeof(glm::vec3));
    const std::vector<std::uint16_t> targets = {2, 0};
    const std::vector<glm::vec3> values = {{0, 4, 0}, {-1, 0, 0}};
    const int target_view = gltf.add_view(targets.data(), targets.size() * sizeof(std::uint16_t));
    const int value_view = gltf.add_view(values.data(), values.size() * sizeof(glm::vec3));
    const int positions =
        gltf.add_accessor({{"bufferView", base},
                           {"componentType", 5126},
                           {"count", 3},
                           {"type", "VEC3"},
                           {"sparse",
                            {{"count", 2},
                             {"indices", {{"bufferView", target_view}, {"componentType", 5123}}},
                             {"values", {{"bufferView", value_view}}}}}});
    gltf.add_root(gltf.add_node({{"mesh", gltf.add_mesh(triangle_primitive(positions))}}));
    const gust::Mesh loaded = load_ok(write("sparse.gltf", gltf.text()));
    EXPECT_EQ(loaded.positions, (std::vector<glm::vec3>{{-1, 0, 0}, {1, 0, 0}, {0, 4, 0}}));
}

TEST_F(ImportTest, usesAllRootNodesWhenTheFileHasNoScene) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    const int child = gltf.add_node({{"mesh", mesh}, {"translation", {0, 0, 1}}});
    gltf.add_node({{"mesh", mesh}, {"children", {child}}});
    gltf.add_node({{"mesh", mesh}, {"translation", {0, 0, 2}}});
    gltf.doc().erase("scenes");
    const gust::Mesh loaded = load_ok(write("noscene.gltf", gltf.text()));
    EXPECT_EQ(loaded.triangle_count(), 3u);
    expect_bounds(loaded, {0, 0, 0}, {1, 1, 2}, 0.0f);
}

TEST_F(ImportTest, usesTheDefaultScene) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    gltf.add_root(gltf.add_node({{"mesh", mesh}}));
    const int far = gltf.add_node({{"mesh", mesh}, {"translation", {0, 0, 9}}});
    gltf.doc()["scenes"].push_back({{"nodes", {far}}});
    gltf.doc()["scene"] = 1;
    const gust::Mesh loaded = load_ok(write("scene1.gltf", gltf.text()));
    EXPECT_EQ(loaded.triangle_count(), 1u);
    expect_bounds(loaded, {0, 0, 9}, {1, 1, 9}, 0.0f);
}

TEST_F(ImportTest, walksVeryDeepNodeChains) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    constexpr int kDepth = 50000;
    int node = gltf.add_node({{"mesh", mesh}});
    for (int i = 1; i < kDepth; ++i)
        node = gltf.add_node({{"children", {node}}, {"translation", {0, 0, 1}}});
    gltf.add_root(node);
    const gust::Mesh loaded = load_ok(write("deep.gltf", gltf.text()));
    expect_bounds(loaded, {0, 0, kDepth - 1}, {1, 1, kDepth - 1}, 0.0f);
}

TEST_F(ImportTest, acceptsRequiredExtensionThatLeavesGeometryAlone) {
    GltfWriter gltf;
    gltf.add_root(
        gltf.add_node({{"mesh", gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)))}}));
    gltf.doc()["extensionsUsed"] = {"KHR_materials_unlit"};
    gltf.doc()["extensionsRequired"] = {"KHR_materials_unlit"};
    EXPECT_EQ(load_ok(write("unlit.gltf", gltf.text())).triangle_count(), 1u);
}

TEST_F(ImportTest, rejectsRequiredMeshCompressionExtension) {
    GltfWriter gltf;
    gltf.add_root(
        gltf.add_node({{"mesh", gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)))}}));
    gltf.doc()["extensionsUsed"] = {"EXT_meshopt_compression"};
    gltf.doc()["extensionsRequired"] = {"EXT_meshopt_compression"};
    expect_failure(write("meshopt.gltf", gltf.text()),
                   "required extension EXT_meshopt_compression is not supported");
}

TEST_F(ImportTest, rejectsAccessorCountMismatch) {
    GltfWriter gltf;
    const int positions = gltf.add_positions(kTriangle);
    const std::vector<glm::vec3> normals(2, glm::vec3(0, 0, 1));
    const int normal = gltf.add_positions(normals);
    gltf.add_root(gltf.add_node(
        {{"mesh",
          gltf.add_mesh(json::array({{{"attributes", {{"POSITION", positions}, {"NORMAL", normal}}}}}))}}));
    expect_failure(write("mismatch.gltf", gltf.text()),
                   "accessor count mismatch: POSITION has 3 elements, NORMAL has 2 in mesh 0 primitive 0");
}

TEST_F(ImportTest, rejectsAccessorReadingPastItsBufferView) {
    GltfWriter gltf;
    const int view = gltf.add_view(kTriangle.data(), kTriangle.size() * sizeof(glm::vec3));
    const int positions =
        gltf.add_accessor({{"bufferView", view}, {"componentType", 5126}, {"count", 6}, {"type", "VEC3"}});
    gltf.add_root(gltf.add_node({{"mesh", gltf.add_mesh(triangle_primitive(positions))}}));
    expect_failure(write("overrun.gltf", gltf.text()), "accessor 0 reads past the end of buffer view 0");
}

TEST_F(ImportTest, rejectsHugeAccessorWithoutBufferView) {
    GltfWriter gltf;
    gltf.add_view(kTriangle.data(), sizeof(glm::vec3) * kTriangle.size()); // the buffer may not be empty
    const int positions =
        gltf.add_accessor({{"componentType", 5126}, {"count", 3000000000u}, {"type", "VEC3"}});
    gltf.add_root(gltf.add_node({{"mesh", gltf.add_mesh(triangle_primitive(positions))}}));
    expect_failure(write("bare.gltf", gltf.text()), "more than the file could describe");
}

TEST_F(ImportTest, rejectsNodeWithTwoParents) {
    GltfWriter gltf;
    const int mesh = gltf.add_mesh(triangle_primitive(gltf.add_positions(kTriangle)));
    const int shared = gltf.add_node({{"mesh", mesh}});
    gltf.add_root(gltf.add_node({{"children", {shared}}}));
    gltf.add_root(gltf.add_node({{"children", {shared}}}));
    expect_failure(write("dag.gltf", gltf.text()), "node 0 has two parents");
}

TEST_F(ImportTest, rejectsTruncatedGlb) {
    const std::string fox = read_file(kAssets / "characters/Fox.glb");
    expect_failure(write("Fox.glb", fox.substr(0, fox.size() - 1000)), "file truncated");
}

TEST_F(ImportTest, rejectsGlbOfAnotherVersion) {
    std::string fox = read_file(kAssets / "characters/Fox.glb");
    fox[4] = 1;
    expect_failure(write("Fox.glb", fox), "unsupported GLB version 1");
}

TEST_F(ImportTest, rejectsGlbDeclaringALengthShorterThanItsHeader) {
    std::string fox = read_file(kAssets / "characters/Fox.glb");
    fox[8] = 10; // total length 10, below the 20-byte header
    fox[9] = fox[10] = fox[11] = 0;
    expect_failure(write("Fox.glb", fox), "GLB header declares a length of 10 bytes");
}

TEST_F(ImportTest, rejectsInvalidJson) {
    expect_failure(write("bad.gltf", "{\"asset\": "), "invalid JSON");
}

// ---------------------------------------------------------------------------------------------------
// validate_mesh and make_box_mesh

TEST(ValidateMesh, acceptsBoxAndNonFinitePositions) {
    gust::Mesh box = gust::make_box_mesh({0, 0, 0}, {1, 1, 1});
    EXPECT_TRUE(gust::validate_mesh(box).ok());
    box.positions[0].x = std::numeric_limits<float>::infinity();
    EXPECT_TRUE(gust::validate_mesh(box).ok());
}

TEST(ValidateMesh, rejectsPartialTriangle) {
    gust::Mesh box = gust::make_box_mesh({0, 0, 0}, {1, 1, 1});
    box.indices.pop_back();
    const gust::Status status = gust::validate_mesh(box);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.message(), "box: index count 35 is not a multiple of 3");
}

TEST(ValidateMesh, rejectsIndexOutOfRange) {
    gust::Mesh box = gust::make_box_mesh({0, 0, 0}, {1, 1, 1});
    box.indices[7] = 8;
    const gust::Status status = gust::validate_mesh(box);
    ASSERT_FALSE(status.ok());
    EXPECT_EQ(status.message(), "box: index 8 out of range (8 vertices) at triangle 2");
}

TEST(MakeBoxMesh, isAClosedOutwardBoxOfTwelveTriangles) {
    const gust::Mesh box = gust::make_box_mesh({-1, 0, 2}, {3, 0.5f, 5});
    EXPECT_EQ(box.positions.size(), 8u);
    EXPECT_EQ(box.triangle_count(), 12u);
    expect_bounds(box, {-1, 0, 2}, {3, 0.5f, 5}, 0.0f);
    EXPECT_NEAR(signed_volume(box), 4.0 * 0.5 * 3.0, 1e-9);
    EXPECT_NEAR(total_area(box), 2.0 * (4.0 * 0.5 + 4.0 * 3.0 + 0.5 * 3.0), 1e-9);
}

} // namespace
