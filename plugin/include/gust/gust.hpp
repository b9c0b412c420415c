// gust: GPU wind for game engines. This header is the manual (docs/api.md has the integration guide).
//
// Every frame the engine tells gust where its meshes are, calls System::step(dt), and reads the wind:
// at points (blocking, or one frame late without a stall), as a 3D texture for its shaders, or as a
// wind-source sample (direction, speed, gust). Nothing here throws: calls return a gust::Outcome whose
// message names the argument and the reason. Units are metres, seconds and m/s; positions and
// directions are world space; matrices are column-major (as GLM, Vulkan and OpenGL store them).
//
// Threading (docs/api.md "Lifetimes and threading"), as Jolt's: one writer, many readers.
// - Writer calls: every member not listed below (create_*, destroy_*, set_*, step, query, query_async,
//   fetch, wind_at, export_vdb, debug_voxels, debug_tree_nodes) and the accessors that return references
//   (stats(), wind_texture()). One thread at a time makes them, which may change from call to call when
//   the host orders the calls (a mutex, a job dependency). A writer call made while another thread is
//   inside one fails with ErrorCode::Busy instead of corrupting the System (a cheap flag, not a lock: it
//   catches overlapping calls, not every race).
// - Reader calls: sample() and read_stats(). Any number of threads may make them at once, also while
//   another thread is inside a writer call (step included). They never block the writer: sample holds the
//   latest published snapshot for the duration of the call, and a step publishing meanwhile fills another
//   copy; read_stats copies under a lock the writer holds only while it stores a frame's statistics.
// - Creation and destruction are neither: no reader may be inside the System when it is destroyed.
// Different Systems may be used from different threads without any ordering.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <span>
#include <string>
#include <vector>
#include <vulkan/vulkan_core.h>

namespace gust {

/// The header's version, passed in SystemDesc so a library built from another version refuses to run.
inline constexpr std::uint32_t kVersionMajor = 0;
inline constexpr std::uint32_t kVersionMinor = 10;
inline constexpr std::uint32_t kVersionPatch = 0;
/// major << 22 | minor << 12 | patch, as VK_MAKE_API_VERSION packs it.
inline constexpr std::uint32_t kHeaderVersion = (kVersionMajor << 22) | (kVersionMinor << 12) | kVersionPatch;
/// The version the library was built as (compare with kHeaderVersion).
std::uint32_t library_version();

/// What went wrong; Ok is 0 (the C ABI uses the same numbers).
enum class ErrorCode : std::int32_t {
    Ok = 0,
    InvalidArgument = 1,   ///< a value out of range, not finite, or of the wrong size
    InvalidHandle = 2,     ///< a mesh, instance or query id that is not (or no longer) alive
    VersionMismatch = 3,   ///< header and library versions differ in major or minor
    DeviceUnsupported = 4, ///< the device lacks a required feature, or no device was found
    DeviceFailure = 5,     ///< a Vulkan call failed (out of device memory, device lost)
    NotReady = 6,          ///< an asynchronous answer is not there yet
    IoError = 7,           ///< a file could not be written
    Unsupported = 8,       ///< built without the optional part this call needs (OpenVDB)
    Busy = 9,              ///< another thread is inside a writer call of this System (header comment)
    NotEnabled = 10,       ///< the System was created without the SystemDesc option this call needs
};

/// The outcome of a call: a code and, when not Ok, a message naming the argument and the reason.
/// (Named apart from the library's internal Status so both can meet in one translation unit.)
class Outcome {
  public:
    Outcome() = default;
    Outcome(ErrorCode code, std::string message) : code_(code), message_(std::move(message)) {}
    explicit operator bool() const { return code_ == ErrorCode::Ok; }
    ErrorCode code() const { return code_; }
    const std::string& message() const { return message_; }

  private:
    ErrorCode code_ = ErrorCode::Ok;
    std::string message_;
};

struct Vec3 {
    float x = 0.0f, y = 0.0f, z = 0.0f;
};

/// Column-major 4x4 matrix (m[12..14] is the translation); identity by default. Transforms are affine: the
/// last row (m[3], m[7], m[11], m[15]) is 0, 0, 0, 1.
struct Mat4 {
    float m[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

/// Severity of a log message.
enum class LogLevel : std::int32_t { Info = 0, Warning = 1, Error = 2 };

/// Host hooks, as plain function pointers with a user pointer (each may be null).
struct Hooks {
    void* user = nullptr;
    /// All host memory gust allocates for a System: the System itself, its meshes, queries and stats,
    /// the voxelizer's and solver's containers, and Vulkan's host allocations (as VkAllocationCallbacks).
    /// Null uses operator new, and the driver's own allocator for Vulkan. Called on the thread that
    /// calls the System. Must return memory aligned to `alignment` (a power of two) or null.
    /// docs/api.md "Host memory" lists what it does not cover (error messages, results handed back).
    void* (*allocate)(void* user, std::size_t bytes, std::size_t alignment) = nullptr;
    /// Frees what `allocate` returned; required when `allocate` is given.
    void (*free)(void* user, void* memory) = nullptr;
    /// Validation-layer and driver messages, pool growth, dropped queries; null drops them. Any thread.
    void (*log)(void* user, LogLevel level, const char* message) = nullptr;
    /// Called when one of gust's internal invariants fails, before the call returns an error; null ignores.
    void (*assert_failed)(void* user, const char* expression, const char* file, int line) = nullptr;
};

/// A host engine's Vulkan device for gust to run on (the second tier; docs/api.md "Devices").
struct HostDevice {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    std::uint32_t queue_family = 0; ///< a family with compute (graphics too for VoxelizePath::Raster)
    std::uint32_t queue_index = 0;  ///< gust submits to this queue (see docs/api.md "Submission")
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr; ///< required
    PFN_vkGetDeviceProcAddr get_device_proc_addr = nullptr;     ///< null: loaded through the above
    /// Device extensions the host enabled (gust uses VK_EXT_conservative_rasterization when listed).
    std::span<const char* const> enabled_extensions;
    /// The instance has VK_EXT_debug_utils enabled: gust names its pipelines and buffers and labels its
    /// passes in the host's command buffers, so RenderDoc or Nsight show them by name.
    bool debug_utils = false;
};

/// What a host must enable on its instance and device before gust can adopt it.
struct DeviceRequirements {
    std::uint32_t api_version = VK_API_VERSION_1_2;
    std::vector<const char*> extensions;          ///< required device extensions
    std::vector<const char*> optional_extensions; ///< used when the host enables them
    std::vector<const char*> features;            ///< names of required VkPhysicalDevice*Features members
};
/// The list a host enables (static strings).
DeviceRequirements device_requirements();
/// Sets gust's required features in `features` and the Vulkan 1.2 feature struct on its pNext chain
/// (which must hold it), leaving the host's other flags as they are.
Outcome add_required_features(VkPhysicalDeviceFeatures2& features);

/// The farthest the focus may be from the world's origin, in cells: 2^19, where a float's step is 1/16 of a
/// cell (a quarter voxel at 4 voxels per cell). Beyond it positions lose the voxels (a focus of 1e30 made
/// every voxel and query land in the wrong place).
inline constexpr float kMaxFocusCells = 524288.0f;

/// Where the wind is simulated and how finely. The longest axis in voxels (cells × voxels_per_cell), rounded
/// up to a power of `branching`, must be at most 1024 (256 cells take 4 voxels per cell at branching 4, 2 at
/// branching 8).
struct WindDomain {
    std::uint32_t cells[3] = {32, 16, 32}; ///< wind cells per axis, each 8..256
    float cell_size = 1.0f;                ///< metres, from 1e-4 · voxels_per_cell to 1000
    std::uint32_t voxels_per_cell = 4;     ///< voxels of the solid boundary per cell per axis, 1..8
    std::uint32_t branching = 4;           ///< the voxel tree's branching per axis: 2, 4 or 8
    Vec3 focus{};                          ///< first centre (player or camera), within 2^19 cells of 0
    /// Steps a tree node stays refined after a moving or deforming surface last reached it (0: coarsened at
    /// the next step); longer keeps the tree steady under surfaces that come and go, at the cost of nodes.
    std::uint32_t hysteresis = 8;
    /// Nested grids around the focus (docs/solver.md "Cascades"), 1..8: cascade k has `cells` cells of
    /// cell_size · ratio^k, the finest first. 1: one grid with the ambient wind beyond it. Queries, wind_at,
    /// query_async and sample answer from the finest cascade that holds the point, blended into the next over
    /// its last cells; each cascade has its own wind texture (wind_textures; gust_wind.glsl blends them as
    /// the answers do, from the same texels) and its own grids in export_vdb; the debug views hold the finest
    /// cascade.
    std::uint32_t cascades = 1;
    std::uint32_t ratio = 4; ///< cell size from one cascade to the next coarser: 2 or 4
};

/// How the wind carries itself along (docs/solver.md, "Advection default" under "One step").
enum class WindAdvection : std::int32_t {
    MacCormack = 0,     ///< second order, clamped: keeps the speed-up beside obstacles over many steps
    SemiLagrangian = 1, ///< first order: a third of the cost, smooths the flow next to obstacles
    None = 2,           ///< not carried, only forced (emitters, ambient wind, confinement): tests, studies
};

/// How the pressure equation is solved (docs/solver.md "Projection").
enum class WindPressure : std::int32_t {
    MultigridPCG = 0, ///< conjugate gradients, a multigrid V-cycle as preconditioner (McAdams et al. 2010)
    Multigrid = 1,    ///< multigrid V-cycles alone
    Jacobi = 2,       ///< the baseline: up to max_iterations sweeps from zero a step (slow; comparisons)
};

/// Numerics of the wind (defaults suit game wind; docs/solver.md explains each).
struct WindSettings {
    float tolerance = 1e-5f;       ///< relative residual the pressure solve stops at
    std::uint32_t max_cycles = 32; ///< V-cycles per step at most (docs/solver.md: about 48 for 128^3)
    float vorticity = 0.2f;        ///< vorticity confinement ε (0: off)
    float viscosity = 0.0f;        ///< m^2/s (0: off)
    WindAdvection advection = WindAdvection::MacCormack;
    /// m/s, in (0, 256]: the fastest a moving surface pushes air; faster surface motion is clamped to it
    /// (docs/solver.md "Motion"). A jump meant as a teleport should say so (set_transform's `teleport`).
    float max_solid_speed = 50.0f;
    /// V-cycles every step runs, a game's fixed per-frame budget: the warm start carries what a step leaves
    /// into the next (docs/solver.md "Per-frame budget"). 0: each step runs until `tolerance` (at most
    /// `max_cycles`), as tools and tests want.
    std::uint32_t cycles_per_step = 2;
    WindPressure pressure = WindPressure::MultigridPCG;
    /// Jacobi only: iterations per step at most, 1..1000000 (run in blocks of 8, each followed by a check
    /// against `tolerance`; the multigrid solvers ignore it and take max_cycles and cycles_per_step).
    std::uint32_t max_iterations = 4000;
};

/// How a System's GPU work reaches a queue.
enum class Submission : std::int32_t {
    OwnQueue = 0,     ///< step(dt) submits and waits on gust's queue (own device) or the host's queue
    HostCommands = 1, ///< host device: step(dt, commands) records the whole frame into the host's buffer
};

/// Which voxelizer path turns triangles into voxels (docs/architecture.md compares them).
enum class VoxelizePath : std::int32_t {
    Auto = 0,    ///< per instance, the path a cost model predicts faster on this device (docs/cli.md)
    Raster = 1,  ///< the hardware rasterizer
    Compute = 2, ///< a thread per triangle
};

/// Everything a System is created from.
struct SystemDesc {
    std::uint32_t header_version = kHeaderVersion; ///< leave as is: checked against the library
    const HostDevice* host = nullptr;              ///< null: gust creates its own instance and device
    bool validation = false;                       ///< own device: enable the Khronos validation layer
    const char* device = nullptr; ///< own device: index or name substring (null: GUST_DEVICE, then best)
    Submission submission = Submission::OwnQueue;
    /// HostCommands: frames the host keeps in flight, 1..8. When step(dt, commands) records frame n, the
    /// command buffer of frame n - frames_in_flight must have completed (docs/api.md "Submission").
    std::uint32_t frames_in_flight = 2;
    VoxelizePath voxelize = VoxelizePath::Auto;
    WindDomain domain;
    WindSettings wind;
    Hooks hooks;
    /// Own device: a file the Vulkan pipeline cache is read from at creation (when it holds this device's
    /// cache, whole; any other file, a missing one included, is ignored) and written to when the System is
    /// destroyed, so the next process creates its pipelines from it instead of compiling them. Only a
    /// missing or empty file or a gust cache (even a damaged one) is replaced, whole; any other file is
    /// left as it is. Its folder is created when missing; a failure to write is ignored. Null: the cache
    /// stays in memory. Read during create().
    const char* pipeline_cache = nullptr;
    /// Publish every step's wind to CPU memory for sample() (any thread, no GPU round trip). It costs host
    /// memory: 8 bytes a cell for each frame in flight (host-visible readback; OwnQueue: one), plus 16 bytes
    /// a cell for each of the 3 published copies: (8 · frames + 48) bytes a cell, 0.9 MB at 32x16x32 with
    /// OwnQueue, 14.7 MB at 64^3, 940 MB at 256^3. A step copies the texels (8 bytes a cell) on the GPU and
    /// converts them to floats on the CPU when the frame is collected.
    bool snapshot = false;
    /// Own device: the physical device whose VkPhysicalDeviceIDProperties::deviceUUID holds these 16 bytes
    /// (read during create(); null: `device`, then GUST_DEVICE, then the best). A host engine that imports
    /// gust's exported copies (below) passes its own device's, since only the same physical device can
    /// import them.
    const std::uint8_t* device_uuid = nullptr;
    /// Own device, 0..8: copies of each cascade's wind texture in memory another VkDevice on the same
    /// physical device imports (VK_KHR_external_memory_fd, which gust's device then needs), so that a host
    /// samples gust's wind with no copy through the CPU and gust never submits on a queue of the host's.
    /// copy_wind_textures writes one of them, export_wind_copy hands out its memory (docs/api.md
    /// "Sharing the wind image with another device"). 0: none.
    std::uint32_t exported_copies = 0;
};

/// How to import one of the wind copies a System exports (System::export_wind_copy) into another VkDevice
/// on the same physical device: a VkImage of exactly this 3D image (1 mip level, 1 layer, optimal tiling,
/// exclusive sharing) with VkExternalMemoryImageCreateInfo{VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT},
/// bound at offset 0 to allocation_size bytes of memory type memory_type_index allocated with
/// VkImportMemoryFdInfoKHR{fd} and VkMemoryDedicatedAllocateInfo{that image} (gust's allocation is
/// dedicated, and an import must match it).
struct ExportedImage {
    int fd = -1; ///< the caller's: a successful import takes it over, otherwise close() it
    VkDeviceSize allocation_size = 0;
    std::uint32_t memory_type_index = 0;
    VkFormat format = VK_FORMAT_R16G16B16A16_SFLOAT;
    std::uint32_t extent[3] = {};
    VkImageUsageFlags usage = 0;
};

/// The VkImageCreateInfo of the image that imports `image` into another device, as ExportedImage describes
/// it, chained to `external` (filled here: opaque file descriptors), which must live until vkCreateImage.
inline VkImageCreateInfo import_image_info(const ExportedImage& image,
                                           VkExternalMemoryImageCreateInfo& external) {
    external = {VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_IMAGE_CREATE_INFO};
    external.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    VkImageCreateInfo info{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO, &external};
    info.imageType = VK_IMAGE_TYPE_3D;
    info.format = image.format;
    info.extent = {image.extent[0], image.extent[1], image.extent[2]};
    info.mipLevels = 1;
    info.arrayLayers = 1;
    info.samples = VK_SAMPLE_COUNT_1_BIT;
    info.tiling = VK_IMAGE_TILING_OPTIMAL;
    info.usage = image.usage;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    return info;
}

/// Ids of meshes and instances: 0 is never valid; a destroyed id is never reused.
using MeshId = std::uint64_t;
using InstanceId = std::uint64_t;

/// Joints and weights of a skinned mesh, four influences a vertex as glTF's JOINTS_0 and WEIGHTS_0 (pad
/// unused ones with weight 0 and any joint in range). Copied to the device by create_mesh; the mesh's
/// positions are then its bind pose, which set_bones' palette moves (docs/api.md "Skinning from bones").
struct MeshSkin {
    std::uint32_t joint_count = 0;         ///< joints of the palette, 1..65536
    const std::uint16_t* joints = nullptr; ///< 4 per vertex, each < joint_count
    const float* weights = nullptr;        ///< 4 per vertex: finite, >= 0, not all 0; used as given (no
                                           ///< normalization: glTF makes them sum to 1)
};

/// A triangle mesh in mesh space: positions with a byte stride (>= 12), 32-bit indices.
struct MeshDesc {
    const float* positions = nullptr;
    std::uint32_t vertex_count = 0;
    std::uint32_t stride = 12; ///< bytes between consecutive positions
    const std::uint32_t* indices = nullptr;
    std::uint32_t index_count = 0; ///< a multiple of 3
    /// Dynamic meshes may change their vertices every frame (set_vertices, set_bones); static ones never do.
    bool deforming = false;
    /// A deforming mesh's skin (null: none), read during create_mesh: its poses may then come from bone
    /// palettes (set_bones), skinned on the GPU, instead of posed vertices.
    const MeshSkin* skin = nullptr;
};

/// A wind source (docs/solver.md "Emitters" draws each profile).
enum class WindEmitterType : std::int32_t {
    Directional = 0,
    Omni = 1, ///< outward from position, added to the solved wind (docs/solver.md, "Emitters")
    Vortex = 2,
    CapsuleMotor = 3,
    ConeMotor = 4
};
struct WindEmitter {
    WindEmitterType type = WindEmitterType::Omni;
    Vec3 position{};         ///< centre, or a motor's start
    Vec3 direction{1, 0, 0}; ///< unit: flow (directional, motors) or axis (vortex)
    float radius = 1.0f;     ///< m, > 0
    float strength = 0.0f;   ///< m/s at the centre (negative reverses)
    float falloff = 1.0f;    ///< exponent of (1 − d/radius), >= 0
    float length = 0.0f;     ///< motors: m along direction
};

/// Wind at a point as engines' wind sources take it.
struct WindSample {
    Vec3 direction{};   ///< unit (0 when still)
    float speed = 0.0f; ///< m/s
    /// Short-term variation, m/s: |velocity − its mean over the neighbouring cells| (what a gust
    /// parameter of a foliage or cloth wind source wants).
    float gust = 0.0f;
};

/// The queue family a System submits to: the host's HostDevice::queue_family, or the one gust chose on its
/// own device (docs/api.md "Devices").
struct QueueInfo {
    std::uint32_t family = 0; ///< queue family index on the System's device
    /// The family has compute without graphics (an async compute queue): gust's work overlaps the host's
    /// rendering on its graphics queue, and the raster voxelizer does not run.
    bool async_compute = false;
};

/// The velocity field as a sampled 3D image for the host's shaders (docs/api.md "Wind texture").
struct WindTexture {
    VkImage image = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
    VkSampler sampler = VK_NULL_HANDLE;              ///< linear, clamp to edge
    VkFormat format = VK_FORMAT_R16G16B16A16_SFLOAT; ///< rgb: m/s, a: 1 − solid fraction
    std::uint32_t extent[3] = {};
    /// World position → texture coordinates in [0, 1]^3 (uvw = world_to_texture · (p, 1)).
    Mat4 world_to_texture;
    /// VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL after each step.
    VkImageLayout layout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    std::uint64_t frame = 0; ///< steps taken when written (0 before any): its step's FrameStats::frame + 1
};

/// What one step did (GPU milliseconds per pass where the device has timestamps).
struct FrameStats {
    std::uint64_t frame = 0;          ///< 0 for the first step
    std::uint64_t fragments = 0;      ///< voxel fragments of the static and moving surfaces
    std::uint64_t voxels = 0;         ///< voxels set in the tree's leaves
    std::uint64_t nodes = 0;          ///< tree nodes, root included
    std::uint64_t refined = 0;        ///< tree blocks handed out this step
    std::uint64_t coarsened = 0;      ///< tree blocks taken back this step
    std::uint64_t pool_bytes = 0;     ///< bytes of live tree blocks
    std::uint64_t fragment_bytes = 0; ///< bytes of the fragment lists
    std::uint64_t dense_bytes = 0;    ///< bytes a dense voxel grid of the same size would take
    float divergence_before = 0.0f;   ///< max |divergence| before projection, 1/s
    float divergence_after = 0.0f;    ///< the same after, 1/s
    float residual = 0.0f;            ///< max |residual| of the pressure solve, 1/s
    std::uint32_t cycles = 0;         ///< V-cycles the solve took (WindPressure::Jacobi: iterations)
    bool converged = false;           ///< the solve met its tolerance
    /// The solve diverged (an inconsistent problem): it was stopped and this step projected nothing, so
    /// the wind stays bounded; converged is false. docs/solver.md "Stability".
    bool diverged = false;
    std::uint32_t sealed_cells = 0;       ///< cells whose air is sealed inside solids (solid for the wind)
    std::uint32_t rejected_triangles = 0; ///< non-finite vertices after transform this frame
    /// The step's GPU work: dispatches and draws recorded (indirect ones counted even when emptied).
    std::uint64_t dispatches = 0;
    /// Its dependent stages: dispatches and draws that wait for the GPU work recorded before them (the first
    /// after each execution barrier). On a GPU a small grid's frame costs about its stages times the time a
    /// barrier takes to drain and launch again, whatever its dispatches (docs/solver.md "Few passes").
    std::uint64_t stages = 0;
    std::uint32_t submissions = 0; ///< queue submissions the step made (HostCommands: 0, the host submits)
    std::uint32_t waits = 0;       ///< times the step waited for the GPU (HostCommands: 0)
    std::uint32_t cut_cells = 0;   ///< wind cells holding solid voxels
    std::uint32_t fluid_cells = 0; ///< wind cells in the pressure solve (with an open face)
    std::uint32_t free_node_blocks = 0; ///< tree node blocks on the free list
    std::uint32_t free_mask_blocks = 0; ///< tree leaf-mask blocks on the free list
    /// Refinements refused because a tree pool was full: that frame's solids were partial, and the pools
    /// grow for the frames after it.
    std::uint32_t exhausted = 0;
    /// Times the tree's pools grew after this step because they ran out in it (exhausted > 0); the frames
    /// recorded from then on use the larger pools.
    std::uint32_t pool_growths = 0;
    bool static_rebuilt = false; ///< the static set was voxelized again (added, moved, removed; a scroll)
    /// Tree nodes per level 1..depth−1, then leaf bricks (the root is level 0), in the System's host memory.
    using Counts = std::pmr::vector<std::uint64_t>;
    Counts nodes_per_level;
    /// GPU milliseconds per pass, in the System's host memory (Hooks::allocate). In a frame where a coarser
    /// cascade steps, its passes follow, named with the prefix "cascade_".
    using Timings = std::pmr::vector<std::pair<std::pmr::string, double>>;
    Timings ms;
};

/// The snapshot a System::sample call answered from.
struct SnapshotInfo {
    std::uint64_t frame = 0;      ///< WindTexture::frame of the step that wrote it (1 after the first)
    Vec3 origin{};                ///< the (finest cascade's) domain's min corner then, m
    float cell_size = 0.0f;       ///< m
    std::uint32_t extent[3] = {}; ///< cells per axis
};

/// What query reads at a point (docs/api.md "One wind at a point"; C: gust_wind_reading).
enum class WindReading : std::int32_t {
    /// The wind at a point, as the wind textures, sample and gust_wind.glsl give it: each cascade's cells
    /// trilinear, blended across the cascades. query's default, and all query_async and wind_at answer.
    Wind = 0,
    /// The solver's own field, resolved below a cell, for tools and physics checks: in the air trilinear on
    /// the faces (closed ones extended from the air), in a solid voxel its solid's velocity, beyond the
    /// finest cascade the coarser cascades' faces blended in time between their steps. It differs from Wind
    /// within a cell of a solid and in shear layers, not elsewhere.
    Solver = 1,
};

/// Ticket of an asynchronous query (0 is never valid).
using QueryId = std::uint64_t;
/// Most points one query (query, query_async) takes; equal to GUST_MAX_QUERY_POINTS.
inline constexpr std::size_t kMaxQueryPoints = std::size_t(1) << 24;

/// The voxel grid of the solid boundary (System::debug_voxel_grid). Voxel (i, j, k) is the world-space box
/// origin + [(i, j, k), (i + 1, j + 1, k + 1)] · voxel_size.
struct VoxelGridInfo {
    Vec3 origin{};                    ///< world-space min corner of voxel (0, 0, 0), m; follows the focus
    float voxel_size = 0.0f;          ///< edge of one voxel, m (cell_size / voxels_per_cell)
    std::uint32_t resolution[3] = {}; ///< voxels per axis, branching^depth (may reach past the wind domain)
    std::uint32_t depth = 0;          ///< tree levels below the root
    std::uint32_t branching = 0;      ///< children per node per axis: 2, 4 or 8
};

/// An occupied voxel, indexed in the grid of System::debug_voxel_grid.
struct VoxelCoord {
    std::uint32_t i = 0, j = 0, k = 0;
};

/// What reached a tree node in the last step (System::debug_tree_nodes).
enum class TreeNodeState : std::int32_t {
    Stale = 0,   ///< no fragment reached it in the last step (coarsened after a few such steps)
    Reached = 1, ///< a moving or deforming surface reached it in the last step
    Static = 2,  ///< static geometry reached it: kept until the static set changes
};

/// One allocated node of the voxel tree as a world-space cube (System::debug_tree_nodes).
struct TreeNode {
    Vec3 min{};              ///< world-space min corner, m
    float size = 0.0f;       ///< edge length, m (branching^(depth − level) voxels)
    std::uint32_t level = 0; ///< 0: the root; depth − 1: leaf bricks of branching^3 voxels
    TreeNodeState state = TreeNodeState::Stale; ///< what reached it in the last step
    bool refined = false;                       ///< has a child block (a leaf brick: an occupancy mask)
};

/// The wind subsystem. Create one per world.
class System {
  public:
    /// Creates the device (or adopts desc.host), the voxel tree and the solver. On failure `out` stays
    /// null and the Outcome says why.
    static Outcome create(const SystemDesc& desc, std::unique_ptr<System>& out);
    /// Waits until the GPU is done with the System's resources (its own device, or on a host device the
    /// queue it was given, where the engine submits the frames recorded for it), then destroys them.
    ~System();
    System(const System&) = delete;
    System& operator=(const System&) = delete;

    /// Uploads a mesh; `id` receives its handle. Indices are checked against vertex_count.
    Outcome create_mesh(const MeshDesc& desc, MeshId& id);
    /// Destroys a mesh; fails with InvalidHandle while an instance still uses it.
    Outcome destroy_mesh(MeshId mesh);
    /// New positions for a deforming mesh (a skinned pose), vertex_count of them with `stride` bytes
    /// between; used from the next step on, the previous pose gives the surface velocity. `teleport`: the
    /// change from the previous pose is a jump (an animation loop's wrap, a new clip), not motion, so the
    /// next step's surfaces of this mesh push no air.
    Outcome set_vertices(MeshId mesh, const float* positions, std::uint32_t vertex_count,
                         std::uint32_t stride = 12, bool teleport = false);
    /// The same from a host VkBuffer (host device only): vertex_count tightly packed float3 at `offset`,
    /// copied at the next step; the host keeps those bytes unchanged until that step's copy has run: until
    /// step() returns (OwnQueue), or the frame it recorded completes (HostCommands). gust cannot know the
    /// buffer's size: the range [offset, offset + 12 vertex_count) must lie inside it.
    Outcome set_vertices(MeshId mesh, VkBuffer buffer, VkDeviceSize offset, std::uint32_t vertex_count,
                         bool teleport = false);
    /// A skinned mesh's pose from its bone palette (MeshDesc::skin): `count` (its joint_count) matrices,
    /// each the joint's transform times its inverse bind matrix, taking bind-pose mesh space to posed mesh
    /// space (the engine folds the inverse bind matrices in, and the skinned node's own transform out, as
    /// glTF engines do). Finite and affine. Copied now; the next step skins the mesh on the GPU into the
    /// positions set_vertices would set, with the same previous-pose and `teleport` rules. The last of
    /// set_vertices and set_bones before a step sets that step's pose.
    Outcome set_bones(MeshId mesh, const Mat4* palette, std::uint32_t count, bool teleport = false);

    /// Places a mesh. Static instances are voxelized once (again only when the static set changes);
    /// moving ones every frame, with velocities from their last transform.
    Outcome create_instance(MeshId mesh, const Mat4& transform, bool moving, InstanceId& id);
    /// Places a moving instance already in motion: `previous` is its transform one step before, so its first
    /// step's surfaces move as that motion does (create_instance's first step moves none). For an object
    /// that was moving before the System saw it: a level loaded mid-motion, a replay started mid-way.
    Outcome create_moving_instance(MeshId mesh, const Mat4& transform, const Mat4& previous, InstanceId& id);
    /// Sets an instance's mesh-to-world transform (finite; a static instance's move re-voxelizes the set).
    /// A moving instance's velocity comes from its last transform; with `teleport` the change is a jump
    /// (a respawn, a cut), so the next step moves the solid without pushing air.
    Outcome set_transform(InstanceId instance, const Mat4& transform, bool teleport = false);
    /// Removes an instance; its mesh may then be destroyed.
    Outcome destroy_instance(InstanceId instance);

    /// Replaces the emitters (at most 64); rejected whole, keeping the old ones, if any is invalid.
    Outcome set_emitters(std::span<const WindEmitter> emitters);
    /// Prevailing wind, m/s: enters through the upwind sides of the domain. A change after the first step
    /// reaches the air of every cascade at the next step (docs/solver.md "Ambient wind").
    Outcome set_ambient(const Vec3& velocity);
    /// Centre of interest; the domain follows it in whole cells at the next step. InvalidArgument (the old
    /// focus kept) for a point more than a million cells from the domain's centre, or more than 2^19 cells
    /// from the world's origin (where floats cannot place voxels; WindDomain::focus likewise).
    Outcome set_focus(const Vec3& position);
    /// For an engine that rebases its world (a floating origin): every world position is now `offset` (m,
    /// finite) away from where it was. gust moves with it: the focus, every cascade's grid and wind, the
    /// emitters, the instances' transforms and the points of queries not yet answered. The next step
    /// voxelizes the static set again in the moved grids; the engine's own later set_transform calls give
    /// positions in the new frame. InvalidArgument (nothing moved) when the new focus would lie more than
    /// 2^19 cells from the world's origin.
    Outcome shift_origin(const Vec3& offset);

    /// Advances the wind by dt seconds (finite, in (0, 10]): voxelize, update the tree, solve, refresh
    /// the wind texture and answer pending queries. Blocks until the GPU is done (Submission::OwnQueue).
    /// After a step fails with DeviceFailure, every later step does too: destroy the System.
    Outcome step(float dt);
    /// The same with Submission::HostCommands: records the whole frame into the host's `commands` (in the
    /// recording state, outside a render pass) and returns without waiting. The host submits the buffers
    /// to the queue in HostDevice in the order recorded. Work and results follow the frame contract of
    /// docs/api.md: stats() and async answers arrive frames_in_flight steps later, and resources gust
    /// replaces or frees are kept until then. After an error `commands` may hold part of a frame: reset it.
    Outcome step(float dt, VkCommandBuffer commands);

    /// Wind velocity at each point (m/s) from the last step, as the wind textures read it (docs/api.md "One
    /// wind at a point"): each cascade's texels trilinear on its cell centres (clamped to the edge), blended
    /// into the next coarser cascade over its last cells as gust_wind.glsl blends them; points beyond the
    /// coarsest cascade get the ambient wind. A cell with air holds its air's velocity, one without air its
    /// solid's. WindReading::Solver reads the solver's field below a cell instead. `velocities` must hold
    /// points.size() entries. Blocks for a GPU round trip.
    Outcome query(std::span<const Vec3> points, std::span<Vec3> velocities,
                  WindReading reading = WindReading::Wind);
    /// Queues the points; the answer is ready after the next step() (frame N's question is answered
    /// with frame N+1's field; HostCommands: once that frame completed, frames_in_flight steps later) and
    /// is fetched with fetch(). Points are copied.
    Outcome query_async(std::span<const Vec3> points, QueryId& id);
    /// The answer to `id` (then forgotten); NotReady before the next step().
    Outcome fetch(QueryId id, std::span<Vec3> velocities);
    /// Reader call (any thread, any number at once, also while another thread steps): the wind at each
    /// point from the latest published snapshot (SystemDesc::snapshot), on the CPU, without waiting for the
    /// GPU. The same wind as query and the wind textures (docs/api.md "One wind at a point"), read from the
    /// same half-float texels: it equals query of the same step within float rounding.
    /// The snapshot is the last step's (OwnQueue: as soon as step() returns; HostCommands: the frame
    /// recorded frames_in_flight steps ago, once collected). It is held for the duration of the call
    /// only: two calls may answer from different steps (`info` says which). A step whose free copies are
    /// all still held by slower readers is not published (the previous stays). NotReady when no step has been
    /// published yet (try again after a step); NotEnabled when the System was created with the snapshot off
    /// (SystemDesc::snapshot), which no step changes; InvalidArgument for a size mismatch or a non-finite
    /// point.
    Outcome sample(std::span<const Vec3> points, std::span<Vec3> velocities) const;
    Outcome sample(std::span<const Vec3> points, std::span<Vec3> velocities, SnapshotInfo& info) const;
    /// Reader call: a copy of the last collected step's statistics (stats() is a writer call). `out`'s
    /// vectors keep their own memory resource.
    Outcome read_stats(FrameStats& out) const;

    /// Wind at one point in the form engines' wind sources use.
    Outcome wind_at(const Vec3& point, WindSample& sample);

    /// The wind texture (valid until the System is destroyed; contents change at each step): the finest
    /// cascade's.
    const WindTexture& wind_texture() const;
    /// Every cascade's wind texture, finest first (WindDomain::cascades of them; the first is
    /// wind_texture()). A coarser cascade's changes at its own steps (its `frame` says which); its
    /// world_to_texture follows its grid. include/gust/gust_wind.glsl picks and blends them in a host's
    /// shaders.
    std::span<const WindTexture> wind_textures() const;
    /// Writer call (SystemDesc::exported_copies): a new file descriptor for the memory of cascade
    /// `cascade`'s copy `slot` (< exported_copies) and what importing it takes. The memory lives as long
    /// as gust's System or an import of it, whichever is longer.
    Outcome export_wind_copy(std::uint32_t cascade, std::uint32_t slot, ExportedImage& out);
    /// Writer call (SystemDesc::exported_copies): copies every cascade's wind texture, as the last step
    /// left it, into its copy `slot`, on gust's queue, and waits for it. The copies are left in
    /// VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL and released to VK_QUEUE_FAMILY_EXTERNAL. Another device
    /// has no semaphore of gust's to wait on, so the host orders the two on the CPU: it stops using copy
    /// `slot` (its frames that read it have completed) before this call and samples it only after it
    /// returns; gust's earlier contents of the slot are discarded (docs/api.md).
    Outcome copy_wind_textures(std::uint32_t slot);
    /// Writer call (read_stats from other threads): the last step's statistics (HostCommands: those of the
    /// frame recorded frames_in_flight steps ago).
    const FrameStats& stats() const;
    /// Where a frame's GPU time goes, for profiling: on, the frames recorded from the next step on time every
    /// dispatch and draw apart, and their FrameStats::ms holds one entry per dispatch in recording order,
    /// named after its pipeline ("gust wind advect", ...), instead of one per pass. Each entry runs from the
    /// end of all the work before it to its own end, so the entries add up to the frame. Off by default;
    /// off again, the next frames give passes. Empty without timestamps (DeviceInfo).
    Outcome set_dispatch_timing(bool on);
    /// The domain's min corner (world, m) after the last step.
    Vec3 domain_origin() const;
    /// The Vulkan device the System runs on (VkPhysicalDeviceProperties::deviceName), valid while it lives.
    const char* device_name() const;
    /// The queue family the System submits to and whether it is an async compute one.
    QueueInfo queue_info() const;
    /// Writes the current frame as OpenVDB (occupancy, solid, velocity, pressure, and each coarser cascade's
    /// velocity_cascadeK, solid_cascadeK and pressure_cascadeK; docs/design.md layout);
    /// Unsupported when the library was built without OpenVDB (GUST_WITH_OPENVDB=OFF).
    Outcome export_vdb(const char* path);

    // Debug views of the solid boundary as of the last step, for tools and samples that draw it. The lists
    // download the tree and walk it on the CPU, blocking for a GPU round trip: not for every frame.

    /// The voxel grid the tree indexes (world space, m). No GPU work.
    Outcome debug_voxel_grid(VoxelGridInfo& info) const;
    /// Occupied leaf voxels (static or moving), ordered by k, then j, then i. `count` receives how many
    /// there are (FrameStats::voxels); the first min(out.size(), count) go into the caller's `out`, so an
    /// empty span asks for the count. Debug only: downloads the tree and blocks.
    Outcome debug_voxels(std::span<VoxelCoord> out, std::size_t& count);
    /// Every allocated tree node (root, internal nodes, leaf bricks), level by level from the root. `count`
    /// receives how many there are (FrameStats::nodes); the first min(out.size(), count) go into the
    /// caller's `out`. Debug only: downloads the node pool and blocks.
    Outcome debug_tree_nodes(std::span<TreeNode> out, std::size_t& count);

    struct Impl;

    /// A System lives in the memory of its Hooks::allocate; delete gives it back there.
    static void operator delete(void* system) noexcept;

  private:
    System() = default;
    static void* operator new(std::size_t bytes, const Hooks& hooks);
    static void operator delete(void* system, const Hooks& hooks) noexcept; ///< when the constructor throws
    Impl* impl_ = nullptr;
};

} // namespace gust
