/* gust: GPU wind for game engines, C ABI. The same API as gust/gust.hpp (which is the manual for what each
 * call does); this header says how it looks from C.
 *
 * Every function returns a gust_result (GUST_OK is 0), except the version and message getters. When a call
 * on a live system fails, gust_system_last_error(system) says which argument and why; when there is no live
 * system to hold the message (gust_system_create, calls given a NULL or destroyed system, free functions),
 * gust_last_create_error() holds it, per thread. Nothing crashes on NULL pointers, unknown ids or destroyed
 * systems. Units are metres, seconds and m/s; positions and directions are world space; matrices are
 * float[16], column-major. Threading as gust.hpp's header says: one writer thread at a time (every call
 * not named here; an overlapping writer call fails with GUST_ERROR_BUSY), and any number of readers at
 * once, also while the writer steps: gust_system_sample. A reader call's or a
 * GUST_ERROR_BUSY failure's message is kept per thread (gust_last_create_error), not in the system.
 * Different systems may be used from different threads.
 *
 * HelloWorld:
 *     gust_system_desc desc;
 *     gust_system_desc_defaults(&desc);
 *     gust_system sys;
 *     if (gust_system_create(&desc, &sys) != GUST_OK) { puts(gust_last_create_error()); return 1; }
 *     gust_vec3 wind = {4, 0, 0};
 *     gust_system_set_ambient(sys, wind);
 *     gust_system_step(sys, 1.0f / 60.0f);
 *     gust_system_destroy(sys);
 */
#ifndef GUST_GUST_H
#define GUST_GUST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <vulkan/vulkan_core.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Major version of this header (gust::kVersionMajor).
#define GUST_VERSION_MAJOR 0
/// Minor version of this header (gust::kVersionMinor).
#define GUST_VERSION_MINOR 10
/// Patch version of this header (gust::kVersionPatch).
#define GUST_VERSION_PATCH 0
/// major << 22 | minor << 12 | patch, as VK_MAKE_API_VERSION packs it; equal to gust::kHeaderVersion.
#define GUST_HEADER_VERSION                                                                                  \
    ((((uint32_t)GUST_VERSION_MAJOR) << 22) | (((uint32_t)GUST_VERSION_MINOR) << 12) |                       \
     ((uint32_t)GUST_VERSION_PATCH))
/// Most emitters gust_system_set_emitters takes at once.
#define GUST_MAX_EMITTERS 64
/// Most points one query (gust_system_query, gust_system_query_async) takes.
#define GUST_MAX_QUERY_POINTS (1u << 24)

/// What went wrong; the same numbers as gust::ErrorCode.
typedef enum gust_result {
    GUST_OK = 0,                     ///< success
    GUST_ERROR_INVALID_ARGUMENT = 1, ///< a NULL pointer; a value out of range, not finite or of a wrong size
    GUST_ERROR_INVALID_HANDLE = 2,   ///< a NULL or destroyed system; a dead mesh, instance or query id
    GUST_ERROR_VERSION_MISMATCH = 3, ///< header and library differ in major or minor version
    GUST_ERROR_DEVICE_UNSUPPORTED = 4, ///< the device lacks a required feature, or no device was found
    GUST_ERROR_DEVICE_FAILURE = 5,     ///< a Vulkan call failed, or host memory ran out
    GUST_ERROR_NOT_READY = 6,          ///< an asynchronous answer is not there yet
    GUST_ERROR_IO = 7,                 ///< a file could not be written
    GUST_ERROR_UNSUPPORTED = 8,        ///< built without the optional part this call needs (OpenVDB)
    GUST_ERROR_BUSY = 9,               ///< another thread is inside a writer call of this system
    GUST_ERROR_NOT_ENABLED =
        10, ///< the system was created without the gust_system_desc option this call needs
} gust_result;

/// The wind subsystem (opaque). Create one per world; a destroyed handle is never reused.
typedef struct gust_system_t* gust_system;
/// A mesh id: 0 is never valid; a destroyed id is never reused.
typedef uint64_t gust_mesh;
/// An instance id: 0 is never valid; a destroyed id is never reused.
typedef uint64_t gust_instance;
/// Ticket of an asynchronous query: 0 is never valid.
typedef uint64_t gust_query;

/// A point, direction or velocity (m, unit, m/s; world space unless stated).
typedef struct gust_vec3 {
    float x, y, z;
} gust_vec3;

/// Severity of a log message.
typedef enum gust_log_level {
    GUST_LOG_INFO = 0,    ///< progress, pool growth
    GUST_LOG_WARNING = 1, ///< something the host may want to fix (dropped queries, validation warnings)
    GUST_LOG_ERROR = 2,   ///< validation-layer and driver errors
} gust_log_level;

/// Host hooks, as plain function pointers with a user pointer; each may be NULL (zero the struct).
typedef struct gust_hooks {
    /// Passed back to every hook; gust never dereferences it.
    void* user;
    /// All host memory gust allocates for a system, Vulkan's host allocations included (docs/api.md "Host
    /// memory"), aligned to `alignment` (a power of two), or NULL; a NULL hook uses the default heap.
    void* (*allocate)(void* user, size_t bytes, size_t alignment);
    /// Frees what `allocate` returned; required when `allocate` is given.
    void (*free)(void* user, void* memory);
    /// Validation-layer and driver messages, pool growth, dropped queries; `message` lives for the call only.
    /// Any thread.
    void (*log)(void* user, gust_log_level level, const char* message);
    /// An internal invariant failed (the call then returns an error); strings live for the call only.
    void (*assert_failed)(void* user, const char* expression, const char* file, int line);
} gust_hooks;

/// A host engine's Vulkan device for gust to run on (the host keeps every handle alive until
/// gust_system_destroy).
typedef struct gust_host_device {
    VkInstance instance;                              ///< the host's instance (apiVersion >= 1.2)
    VkPhysicalDevice physical_device;                 ///< the device's physical device
    VkDevice device;                                  ///< created with gust_add_required_features
    uint32_t queue_family;                            ///< a family with compute (graphics: raster too)
    uint32_t queue_index;                             ///< gust submits to this queue of the family
    PFN_vkGetInstanceProcAddr get_instance_proc_addr; ///< required
    PFN_vkGetDeviceProcAddr get_device_proc_addr;     ///< NULL: loaded through get_instance_proc_addr
    const char* const* enabled_extensions;            ///< device extensions the host enabled; read in create
    uint32_t enabled_extension_count;                 ///< entries in enabled_extensions
    bool debug_utils; ///< the instance has VK_EXT_debug_utils: gust names its pipelines, buffers and passes
} gust_host_device;

/// What a host enables on its instance and device before gust can adopt it (arrays and strings are static).
typedef struct gust_device_requirements {
    uint32_t api_version;                   ///< lowest Vulkan API version (VK_API_VERSION_1_2)
    uint32_t extension_count;               ///< entries in extensions
    const char* const* extensions;          ///< required device extensions
    uint32_t optional_extension_count;      ///< entries in optional_extensions
    const char* const* optional_extensions; ///< used when the host enables and lists them
    uint32_t feature_count;                 ///< entries in features
    const char* const* features;            ///< names of required VkPhysicalDevice*Features members
} gust_device_requirements;

/// Where the wind is simulated and how finely. The longest axis in voxels (cells x voxels_per_cell), rounded
/// up to a power of the branching, must be at most 1024.
typedef struct gust_wind_domain {
    uint32_t cells[3];        ///< wind cells per axis, each 8..256
    float cell_size;          ///< metres, from 1e-4 x voxels_per_cell to 1000
    uint32_t voxels_per_cell; ///< voxels of the solid boundary per cell per axis, 1..8
    uint32_t branching;       ///< the voxel tree's branching per axis: 2, 4 or 8
    gust_vec3 focus;          ///< first centre (player or camera), world m, within 2^19 cells of 0
    uint32_t hysteresis;      ///< steps a tree node stays refined after a moving surface left it (default 8)
    uint32_t cascades;        ///< nested grids around the focus, 1..8 (default 1: one grid; gust::WindDomain)
    uint32_t ratio;           ///< cell size from one cascade to the next coarser: 2 or 4 (default 4)
} gust_wind_domain;

/// What gust_system_query_reading reads at a point (gust::WindReading).
typedef enum gust_wind_reading {
    GUST_WIND_READING_WIND = 0,   ///< the wind at a point, as the textures and gust_system_sample give it
    GUST_WIND_READING_SOLVER = 1, ///< the solver's own field, resolved below a cell
    /// Not a reading: keeps the type 32 bits wide, so any value a caller passes is one the library may
    /// read and refuse (GUST_ERROR_INVALID_ARGUMENT), as Vulkan's *_MAX_ENUM values do.
    GUST_WIND_READING_MAX_ENUM = 0x7fffffff,
} gust_wind_reading;

/// How the wind carries itself along (gust::WindAdvection).
typedef enum gust_advection {
    GUST_ADVECTION_MACCORMACK = 0,      ///< second order, clamped (the default)
    GUST_ADVECTION_SEMI_LAGRANGIAN = 1, ///< first order: cheaper, smooths the flow next to obstacles
    GUST_ADVECTION_NONE = 2,            ///< the air is not carried, only forced (tests, studies)
} gust_advection;

/// How the pressure equation is solved (gust::WindPressure).
typedef enum gust_pressure {
    GUST_PRESSURE_MULTIGRID_PCG = 0, ///< conjugate gradients preconditioned by a V-cycle each (the default)
    GUST_PRESSURE_MULTIGRID = 1,     ///< multigrid V-cycles alone
    GUST_PRESSURE_JACOBI = 2,        ///< the baseline: up to max_iterations Jacobi sweeps a step, from zero
} gust_pressure;

/// Numerics of the wind (the defaults suit game wind; docs/solver.md explains each).
typedef struct gust_wind_settings {
    float tolerance;          ///< relative residual the pressure solve stops at
    uint32_t max_cycles;      ///< V-cycles per step at most
    float vorticity;          ///< vorticity confinement epsilon (0: off)
    float viscosity;          ///< m^2/s (0: off)
    gust_advection advection; ///< GUST_ADVECTION_MACCORMACK by default
    float max_solid_speed;    ///< m/s, in (0, 256]: the fastest a moving surface pushes air (default 50)
    uint32_t cycles_per_step; ///< V-cycles every step runs (default 2); 0: until the tolerance
    gust_pressure pressure;   ///< GUST_PRESSURE_MULTIGRID_PCG by default
    uint32_t max_iterations;  ///< Jacobi only: iterations a step at most, 1..1000000 (default 4000)
} gust_wind_settings;

/// How a system's GPU work reaches a queue.
typedef enum gust_submission {
    GUST_SUBMISSION_OWN_QUEUE = 0,     ///< gust_system_step submits and waits on gust's or the host's queue
    GUST_SUBMISSION_HOST_COMMANDS = 1, ///< host device only: gust_system_step_commands records the frame
} gust_submission;

/// Which voxelizer path turns triangles into voxels (docs/architecture.md compares them).
typedef enum gust_voxelize_path {
    GUST_VOXELIZE_AUTO = 0,    ///< per instance, the path a cost model predicts faster (docs/cli.md)
    GUST_VOXELIZE_RASTER = 1,  ///< the hardware rasterizer
    GUST_VOXELIZE_COMPUTE = 2, ///< a thread per triangle
} gust_voxelize_path;

/// Everything a system is created from; fill with gust_system_desc_defaults, then change what differs.
typedef struct gust_system_desc {
    uint32_t header_version;      ///< GUST_HEADER_VERSION (set by gust_system_desc_defaults); keep first
    const gust_host_device* host; ///< NULL: gust creates its own instance and device; read in create
    bool validation;              ///< own device: enable the Khronos validation layer
    const char* device;           ///< own device: index or name substring (NULL: GUST_DEVICE, then best)
    gust_submission submission;   ///< how GPU work reaches a queue
    uint32_t frames_in_flight;    ///< host commands: frames the host keeps in flight, 1..8 (default 2)
    gust_voxelize_path voxelize;  ///< voxelizer path
    gust_wind_domain domain;      ///< the simulated box
    gust_wind_settings wind;      ///< solver numerics
    gust_hooks hooks;             ///< host hooks (copied; the functions must stay valid until destroy)
    /// Own device: a pipeline cache file, read in create (when it holds this device's cache) and written by
    /// gust_system_destroy, so the next process need not compile its pipelines; NULL keeps it in memory.
    /// Only a missing or empty file or a gust cache is replaced; any other file is left as it is.
    const char* pipeline_cache;
    /// Publish each step's wind to CPU memory for gust_system_sample (gust::SystemDesc::snapshot: 8 bytes a
    /// cell per frame in flight plus 48 bytes a cell).
    bool snapshot;
    /// Own device: the physical device whose deviceUUID holds these 16 bytes (gust::SystemDesc::device_uuid);
    /// NULL: `device`, then GUST_DEVICE, then the best.
    const uint8_t* device_uuid;
    /// Own device, 0..8: exported copies of each cascade's wind texture for another VkDevice
    /// (gust::SystemDesc::exported_copies; gust_system_export_wind_copy, gust_system_copy_wind_textures).
    uint32_t exported_copies;
} gust_system_desc;

/// How another VkDevice imports one exported wind copy (gust::ExportedImage has the rules).
typedef struct gust_exported_image {
    int fd; ///< the caller's: a successful import takes it over, otherwise close() it
    VkDeviceSize allocation_size;
    uint32_t memory_type_index;
    VkFormat format;
    uint32_t extent[3];
    VkImageUsageFlags usage;
} gust_exported_image;

/// Joints and weights of a skinned mesh, four influences a vertex as glTF's JOINTS_0 and WEIGHTS_0
/// (gust::MeshSkin); the mesh's positions are its bind pose, which gust_system_set_bones' palette moves.
typedef struct gust_mesh_skin {
    uint32_t joint_count;   ///< joints of the palette, 1..65536
    const uint16_t* joints; ///< 4 per vertex, each < joint_count
    const float* weights;   ///< 4 per vertex: finite, >= 0, not all 0; used as given (not normalized)
} gust_mesh_skin;

/// A triangle mesh in mesh space: positions with a byte stride (>= 12), 32-bit indices; read during the call.
typedef struct gust_mesh_desc {
    const float* positions;     ///< vertex_count positions, x y z floats, `stride` bytes apart
    uint32_t vertex_count;      ///< positions
    uint32_t stride;            ///< bytes between consecutive positions
    const uint32_t* indices;    ///< index_count indices, each < vertex_count
    uint32_t index_count;       ///< a multiple of 3
    bool deforming;             ///< true: vertices may change every frame (gust_system_set_vertices,
                                ///< gust_system_set_bones)
    const gust_mesh_skin* skin; ///< a deforming mesh's skin, or NULL (gust::MeshDesc::skin)
} gust_mesh_desc;

/// A wind source's profile (docs/solver.md "Emitters" draws each).
typedef enum gust_wind_emitter_type {
    GUST_WIND_EMITTER_DIRECTIONAL = 0,   ///< flow along direction within radius
    GUST_WIND_EMITTER_OMNI = 1,          ///< outward from position, added to the solved wind
    GUST_WIND_EMITTER_VORTEX = 2,        ///< swirl about direction
    GUST_WIND_EMITTER_CAPSULE_MOTOR = 3, ///< flow along a capsule from position, length along direction
    GUST_WIND_EMITTER_CONE_MOTOR = 4,    ///< flow along a cone from position, length along direction
} gust_wind_emitter_type;

/// A wind source; fill with gust_wind_emitter_defaults, then change what differs.
typedef struct gust_wind_emitter {
    gust_wind_emitter_type type; ///< profile
    gust_vec3 position;          ///< centre, or a motor's start (world m)
    gust_vec3 direction;         ///< unit: flow (directional, motors) or axis (vortex)
    float radius;                ///< m, > 0
    float strength;              ///< m/s at the centre (negative reverses)
    float falloff;               ///< exponent of (1 - d/radius), >= 0
    float length;                ///< motors: m along direction
} gust_wind_emitter;

/// Wind at a point as engines' wind sources take it.
typedef struct gust_wind_sample {
    gust_vec3 direction; ///< unit (0 when still)
    float speed;         ///< m/s
    float gust;          ///< short-term variation, m/s: |velocity - its mean over the neighbouring cells|
} gust_wind_sample;

/// The velocity field as a sampled 3D image for the host's shaders; handles owned by the system.
typedef struct gust_wind_texture {
    VkImage image;              ///< valid until gust_system_destroy; contents change at each step
    VkImageView view;           ///< 3D view of image
    VkSampler sampler;          ///< linear, clamp to edge
    VkFormat format;            ///< rgb: m/s, a: 1 - solid fraction
    uint32_t extent[3];         ///< texels per axis
    float world_to_texture[16]; ///< column-major: uvw = world_to_texture * (p, 1), domain -> [0, 1]^3
    VkImageLayout layout;       ///< VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL after each step
    uint64_t frame;             ///< steps taken when written (0 before any): its step's stats frame + 1
} gust_wind_texture;

/// The queue family a system submits to (gust::QueueInfo).
typedef struct gust_queue_info {
    uint32_t family;    ///< queue family index on the system's device
    bool async_compute; ///< compute without graphics: beside the host's graphics queue; no raster voxelizer
} gust_queue_info;

/// What one step did; per-pass GPU milliseconds via gust_system_stats_pass.
typedef struct gust_frame_stats {
    uint64_t frame;              ///< the frame these statistics describe
    uint64_t fragments;          ///< voxel fragments this frame
    uint64_t voxels;             ///< occupied voxels
    uint64_t nodes;              ///< tree nodes
    uint64_t refined;            ///< nodes refined this frame
    uint64_t coarsened;          ///< nodes coarsened this frame
    uint64_t pool_bytes;         ///< bytes of the tree's node pool
    uint64_t fragment_bytes;     ///< bytes of the fragment list
    uint64_t dense_bytes;        ///< bytes a dense voxel grid of the domain would take
    float divergence_before;     ///< max |divergence| before projection, 1/s
    float divergence_after;      ///< max |divergence| after projection, 1/s
    float residual;              ///< max |residual| at the solve's last check, 1/s
    uint32_t cycles;             ///< V-cycles (Jacobi: iterations) the pressure solve ran
    uint32_t sealed_cells;       ///< cells whose air is sealed inside solids (solid for the wind)
    uint32_t rejected_triangles; ///< triangles with non-finite vertices after transform this frame
    uint64_t dispatches;         ///< GPU dispatches and draws the step recorded (indirect ones included)
    uint64_t stages;             ///< its dependent stages: dispatches and draws after an execution barrier
    uint32_t submissions;        ///< queue submissions the step made (host commands: 0)
    uint32_t waits;              ///< times the step waited for the GPU (host commands: 0)
    uint32_t cut_cells;          ///< wind cells holding solid voxels
    uint32_t fluid_cells;        ///< wind cells in the pressure solve
    uint32_t free_node_blocks;   ///< tree node blocks on the free list
    uint32_t free_mask_blocks;   ///< tree leaf-mask blocks on the free list
    uint32_t exhausted;          ///< refinements refused by a full pool (that frame's solids were partial)
    uint32_t pool_growths;       ///< times the tree's pools grew because they ran out in this step
    bool converged;              ///< the pressure solve reached the tolerance
    bool diverged;               ///< the solve diverged and was stopped; the step projected nothing
    bool static_rebuilt;         ///< the static set was voxelized again
} gust_frame_stats;

/// The voxel grid of the solid boundary (gust_system_debug_voxel_grid). Voxel (i, j, k) is the world-space
/// box origin + [(i, j, k), (i + 1, j + 1, k + 1)] * voxel_size.
typedef struct gust_voxel_grid_info {
    gust_vec3 origin;       ///< world-space min corner of voxel (0, 0, 0), m; follows the focus
    float voxel_size;       ///< edge of one voxel, m (cell_size / voxels_per_cell)
    uint32_t resolution[3]; ///< voxels per axis, branching^depth (may reach past the wind domain)
    uint32_t depth;         ///< tree levels below the root
    uint32_t branching;     ///< children per node per axis: 2, 4 or 8
} gust_voxel_grid_info;

/// An occupied voxel, indexed in the grid of gust_system_debug_voxel_grid.
typedef struct gust_voxel_coord {
    uint32_t i, j, k; ///< voxel indices along x, y and z
} gust_voxel_coord;

/// What reached a tree node in the last step (gust::TreeNodeState).
typedef enum gust_tree_node_state {
    GUST_TREE_NODE_STALE = 0, ///< no fragment reached it in the last step (coarsened after a few such steps)
    GUST_TREE_NODE_REACHED = 1, ///< a moving or deforming surface reached it in the last step
    GUST_TREE_NODE_STATIC = 2,  ///< static geometry reached it: kept until the static set changes
} gust_tree_node_state;

/// One allocated node of the voxel tree as a world-space cube (gust_system_debug_tree_nodes).
typedef struct gust_tree_node {
    gust_vec3 min;              ///< world-space min corner, m
    float size;                 ///< edge length, m (branching^(depth - level) voxels)
    uint32_t level;             ///< 0: the root; depth - 1: leaf bricks of branching^3 voxels
    gust_tree_node_state state; ///< what reached it in the last step
    bool refined;               ///< has a child block (a leaf brick: an occupancy mask)
} gust_tree_node;

/// The version the library was built as (compare with GUST_HEADER_VERSION). Any thread.
uint32_t gust_library_version(void);

/// This thread's message of the last failure that had no live system to hold it ("" if none); valid until
/// this thread's next such failure.
const char* gust_last_create_error(void);

/// Fills `requirements` with what a host device needs (static arrays, valid for the process). Any thread.
gust_result gust_get_device_requirements(gust_device_requirements* requirements);

/// Sets gust's required features in `features` and the Vulkan 1.2 feature struct on its pNext chain (which
/// must hold it), leaving the host's other flags as they are. Any thread.
gust_result gust_add_required_features(VkPhysicalDeviceFeatures2* features);

/// Fills `desc` with the library's defaults stamped with `header_version`; refuses (writing only
/// header_version) when that differs from the library in major or minor. Use gust_system_desc_defaults.
gust_result gust_system_desc_init(gust_system_desc* desc, uint32_t header_version);

/// Fills `desc` with gust::SystemDesc's defaults (own device, 32x16x32 cells of 1 m, own queue, automatic
/// voxelizer path, no hooks) stamped with this header's version.
static inline gust_result gust_system_desc_defaults(gust_system_desc* desc) {
    return gust_system_desc_init(desc, GUST_HEADER_VERSION);
}

/// Fills `desc` with the defaults (no geometry, stride 12, not deforming).
gust_result gust_mesh_desc_defaults(gust_mesh_desc* desc);

/// Fills `emitter` with the defaults (omni at the origin, direction +x, radius 1, strength 0, falloff 1).
gust_result gust_wind_emitter_defaults(gust_wind_emitter* emitter);

/// Creates the device (or adopts desc->host), the voxel tree and the solver into `*system`; on failure
/// `*system` is NULL and gust_last_create_error() says why. Any thread.
gust_result gust_system_create(const gust_system_desc* desc, gust_system* system);

/// Waits for the GPU (its own device, or on a host device the queue it was given) and destroys `system`
/// and everything it owns; the handle is dead afterwards.
gust_result gust_system_destroy(gust_system system);

/// The message of the last failed call on `system` ("" if none), owned by the system and valid until the
/// next call on it; for a NULL or destroyed handle, gust_last_create_error().
const char* gust_system_last_error(gust_system system);

/// Uploads a mesh (read during the call); `*mesh` receives its id. Indices are checked against vertex_count.
gust_result gust_system_create_mesh(gust_system system, const gust_mesh_desc* desc, gust_mesh* mesh);

/// Destroys a mesh; GUST_ERROR_INVALID_HANDLE while an instance still uses it.
gust_result gust_system_destroy_mesh(gust_system system, gust_mesh mesh);

/// New mesh-space positions for a deforming mesh (vertex_count of them, `stride` bytes apart, read during the
/// call), used from the next step on; the previous pose gives the surface velocity. `teleport`: the change is
/// a jump (an animation loop's wrap), so the next step's surfaces of this mesh push no air.
gust_result gust_system_set_vertices(gust_system system, gust_mesh mesh, const float* positions,
                                     uint32_t vertex_count, uint32_t stride, bool teleport);

/// The same from a host VkBuffer (host device only): vertex_count packed float3 at `offset` bytes, copied on
/// gust's queue at the next step; the host keeps those bytes unchanged until that step's copy has run
/// (gust_system_step returns, or with host commands the frame completes). gust cannot know the buffer's size:
/// the range [offset, offset + 12 vertex_count) must lie inside it.
gust_result gust_system_set_vertices_buffer(gust_system system, gust_mesh mesh, VkBuffer buffer,
                                            VkDeviceSize offset, uint32_t vertex_count, bool teleport);

/// A skinned mesh's pose from its bone palette (gust::System::set_bones): `count` (its joint_count)
/// column-major 4x4 matrices, 16 floats each, read during the call: each joint's transform times its inverse
/// bind matrix, bind-pose mesh space to posed mesh space. The next step skins the mesh on the GPU, with
/// set_vertices' rules for the previous pose and `teleport`.
gust_result gust_system_set_bones(gust_system system, gust_mesh mesh, const float* palette, uint32_t count,
                                  bool teleport);

/// Places `mesh` with a column-major mesh-to-world `transform` (16 finite floats); moving instances are
/// voxelized every frame, static ones once. `*instance` receives its id.
gust_result gust_system_create_instance(gust_system system, gust_mesh mesh, const float transform[16],
                                        bool moving, gust_instance* instance);

/// Places a moving instance already in motion: `previous` (16 finite floats) is its transform one step
/// before, so its first step's surfaces move as that motion does (gust_system_create_instance's first step
/// moves none). `*instance` receives its id.
gust_result gust_system_create_moving_instance(gust_system system, gust_mesh mesh, const float transform[16],
                                               const float previous[16], gust_instance* instance);

/// Sets an instance's column-major mesh-to-world transform (16 finite floats). `teleport`: the change is a
/// jump (a respawn, a cut), so the next step moves the solid without pushing air.
gust_result gust_system_set_transform(gust_system system, gust_instance instance, const float transform[16],
                                      bool teleport);

/// Removes an instance; its id is dead afterwards.
gust_result gust_system_destroy_instance(gust_system system, gust_instance instance);

/// Replaces the emitters with `count` (<= GUST_MAX_EMITTERS) copied from `emitters` (NULL when count is 0);
/// rejected whole, keeping the old ones, if any is invalid.
gust_result gust_system_set_emitters(gust_system system, const gust_wind_emitter* emitters, size_t count);

/// Prevailing wind, m/s world: enters through the upwind sides of the domain; a change after the first step
/// reaches the air of every cascade at the next step (docs/solver.md "Ambient wind").
gust_result gust_system_set_ambient(gust_system system, gust_vec3 velocity);

/// Centre of interest (world m); the domain follows it in whole cells at the next step. Invalid (the old
/// focus kept) for a point more than a million cells from the domain's centre, or more than 2^19 cells
/// from the world's origin (where floats cannot place voxels; the domain's first focus likewise).
gust_result gust_system_set_focus(gust_system system, gust_vec3 position);

/// For an engine that rebases its world: every world position is now `offset` away
/// (gust::System::shift_origin). The focus, the grids and wind, emitters, instances and unanswered query
/// points move with it.
gust_result gust_system_shift_origin(gust_system system, gust_vec3 offset);

/// Advances the wind by dt seconds (finite, in (0, 10]): voxelize, update the tree, solve, refresh the wind
/// texture and answer pending queries. Blocks until the GPU is done (GUST_SUBMISSION_OWN_QUEUE).
gust_result gust_system_step(gust_system system, float dt);

/// The same with GUST_SUBMISSION_HOST_COMMANDS: records the whole frame into the host's `commands`
/// (recording state, outside a render pass) without waiting. When frame n is recorded, the host's command
/// buffer of frame n - frames_in_flight must have completed; stats and async answers arrive then
/// (docs/api.md "Submission").
gust_result gust_system_step_commands(gust_system system, float dt, VkCommandBuffer commands);

/// Wind velocity (m/s) at `count` points into `velocities` (count entries, caller-owned), as the wind
/// textures and gust_system_sample give it (GUST_WIND_READING_WIND); points outside the domain get the
/// ambient wind. Blocks for a GPU round trip.
gust_result gust_system_query(gust_system system, const gust_vec3* points, size_t count,
                              gust_vec3* velocities);

/// gust_system_query reading `reading` (gust::WindReading): GUST_WIND_READING_SOLVER reads the solver's
/// own field below a cell, for tools and physics checks.
gust_result gust_system_query_reading(gust_system system, const gust_vec3* points, size_t count,
                                      gust_vec3* velocities, gust_wind_reading reading);

/// Reader call (any thread, while another steps): wind velocity (m/s) at `count` points from the latest
/// snapshot published to CPU memory (gust_system_desc::snapshot), without the GPU; gust::System::sample
/// says how it matches gust_system_query. `*frame` (may be NULL) receives the step it answered from.
/// GUST_ERROR_NOT_READY when nothing is published yet (try again after a step); GUST_ERROR_NOT_ENABLED when
/// the system was created with the snapshot off (gust_system_desc::snapshot), which no step changes.
gust_result gust_system_sample(gust_system system, const gust_vec3* points, size_t count,
                               gust_vec3* velocities, uint64_t* frame);

/// Queues `count` points (copied); the answer is ready after the next step and is fetched with
/// gust_system_fetch. `*query` receives its ticket.
gust_result gust_system_query_async(gust_system system, const gust_vec3* points, size_t count,
                                    gust_query* query);

/// Writes the answer to `query` (count = the queued points' count, caller-owned) and forgets it;
/// GUST_ERROR_NOT_READY before the next step.
gust_result gust_system_fetch(gust_system system, gust_query query, gust_vec3* velocities, size_t count);

/// Wind at one world point (m) in the form engines' wind sources use.
gust_result gust_system_wind_at(gust_system system, gust_vec3 point, gust_wind_sample* sample);

/// Fills `texture` with the wind texture's handles and mapping (handles owned by the system): the finest
/// cascade's.
gust_result gust_system_wind_texture(gust_system system, gust_wind_texture* texture);

/// Fills `texture` with cascade `cascade`'s wind texture (0: the finest, as gust_system_wind_texture; up to
/// domain.cascades - 1); GUST_INVALID_ARGUMENT beyond the last. gust_wind.glsl blends them.
gust_result gust_system_cascade_texture(gust_system system, uint32_t cascade, gust_wind_texture* texture);

/// Fills `stats` with the last step's statistics (a writer call; gust::System::read_stats is the reader's).
gust_result gust_system_stats(gust_system system, gust_frame_stats* stats);

/// Tree nodes per level of the last step's statistics (levels 1..depth-1, then leaf bricks): `*count`
/// receives the number of levels and the first min(capacity, *count) go into `nodes` (NULL with capacity 0
/// asks for the count).
gust_result gust_system_stats_nodes_per_level(gust_system system, uint64_t* nodes, uint32_t capacity,
                                              uint32_t* count);

/// `*count` receives how many timed GPU passes the last step's statistics hold (0 without timestamps).
gust_result gust_system_stats_pass_count(gust_system system, uint32_t* count);

/// Pass `index` (< gust_system_stats_pass_count) of the last step: `*name` (owned by the system, valid until
/// the next step) and `*ms` (GPU milliseconds); either output may be NULL.
gust_result gust_system_stats_pass(gust_system system, uint32_t index, const char** name, double* ms);

/// On: the frames recorded from the next step on time every dispatch and draw apart, and the statistics'
/// passes (gust_system_stats_pass) are those dispatches, named after their pipelines
/// (gust::System::set_dispatch_timing). Off by default.
gust_result gust_system_set_dispatch_timing(gust_system system, bool on);

/// A new file descriptor for the memory of cascade `cascade`'s exported wind copy `slot`, and how to import
/// it (gust::System::export_wind_copy).
gust_result gust_system_export_wind_copy(gust_system system, uint32_t cascade, uint32_t slot,
                                         gust_exported_image* image);

/// Copies every cascade's wind texture into its exported copy `slot` and waits, leaving the copies released
/// to VK_QUEUE_FAMILY_EXTERNAL in SHADER_READ_ONLY_OPTIMAL (gust::System::copy_wind_textures).
gust_result gust_system_copy_wind_textures(gust_system system, uint32_t slot);

/// `*origin` receives the domain's min corner (world m) after the last step.
gust_result gust_system_domain_origin(gust_system system, gust_vec3* origin);

/// `*name` receives the name of the Vulkan device the system runs on (owned by the system, valid until
/// gust_system_destroy).
gust_result gust_system_device_name(gust_system system, const char** name);

/// `*info` receives the queue family the system submits to and whether it is an async compute one
/// (gust::System::queue_info).
gust_result gust_system_queue_info(gust_system system, gust_queue_info* info);

/// Writes the current frame as OpenVDB to `path` (occupancy, solid, velocity, pressure; docs/design.md
/// layout); GUST_ERROR_UNSUPPORTED when built without OpenVDB (GUST_WITH_OPENVDB=OFF).
gust_result gust_system_export_vdb(gust_system system, const char* path);

/* Debug views of the solid boundary as of the last step, for tools and samples that draw it. The lists
 * download the tree and walk it on the CPU, blocking for a GPU round trip: not for every frame. */

/// Fills `info` with the voxel grid the tree indexes (world space, m). No GPU work.
gust_result gust_system_debug_voxel_grid(gust_system system, gust_voxel_grid_info* info);

/// Occupied leaf voxels (static or moving), ordered by k, then j, then i: `*count` receives how many there
/// are and the first min(capacity, *count) go into the caller's `voxels` (NULL when capacity is 0, to ask for
/// the count). Debug only: downloads the tree and blocks.
gust_result gust_system_debug_voxels(gust_system system, gust_voxel_coord* voxels, size_t capacity,
                                     size_t* count);

/// Every allocated tree node, level by level from the root: `*count` receives how many there are and the
/// first min(capacity, *count) go into the caller's `nodes` (NULL when capacity is 0). Debug only: downloads
/// the node pool and blocks.
gust_result gust_system_debug_tree_nodes(gust_system system, gust_tree_node* nodes, size_t capacity,
                                         size_t* count);

#ifdef __cplusplus
} // extern "C"
#endif

#endif /* GUST_GUST_H */
