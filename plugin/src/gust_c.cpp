// The C ABI (gust.h) over gust::System. Systems are handed out as serial numbers looked up in a registry,
// so a NULL, destroyed or made-up handle fails with GUST_ERROR_INVALID_HANDLE instead of being dereferenced,
// and a destroyed handle never aliases a later system. Messages live in the system (or, without one, in
// thread-local storage), and no C++ exception crosses into C.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <exception>
#include <gust/gust.h>
#include <gust/gust.hpp>
#include <memory>
#include <mutex>
#include <new>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

static_assert(GUST_VERSION_MAJOR == gust::kVersionMajor && GUST_VERSION_MINOR == gust::kVersionMinor &&
              GUST_VERSION_PATCH == gust::kVersionPatch);
static_assert(GUST_HEADER_VERSION == gust::kHeaderVersion);
static_assert(GUST_MAX_QUERY_POINTS == gust::kMaxQueryPoints);

static_assert(GUST_OK == static_cast<int>(gust::ErrorCode::Ok));
static_assert(GUST_ERROR_INVALID_ARGUMENT == static_cast<int>(gust::ErrorCode::InvalidArgument));
static_assert(GUST_ERROR_INVALID_HANDLE == static_cast<int>(gust::ErrorCode::InvalidHandle));
static_assert(GUST_ERROR_VERSION_MISMATCH == static_cast<int>(gust::ErrorCode::VersionMismatch));
static_assert(GUST_ERROR_DEVICE_UNSUPPORTED == static_cast<int>(gust::ErrorCode::DeviceUnsupported));
static_assert(GUST_ERROR_DEVICE_FAILURE == static_cast<int>(gust::ErrorCode::DeviceFailure));
static_assert(GUST_ERROR_NOT_READY == static_cast<int>(gust::ErrorCode::NotReady));
static_assert(GUST_ERROR_IO == static_cast<int>(gust::ErrorCode::IoError));
static_assert(GUST_ERROR_UNSUPPORTED == static_cast<int>(gust::ErrorCode::Unsupported));

static_assert(GUST_LOG_INFO == static_cast<int>(gust::LogLevel::Info));
static_assert(GUST_LOG_WARNING == static_cast<int>(gust::LogLevel::Warning));
static_assert(GUST_LOG_ERROR == static_cast<int>(gust::LogLevel::Error));

static_assert(GUST_ADVECTION_MACCORMACK == static_cast<int>(gust::WindAdvection::MacCormack));
static_assert(GUST_ADVECTION_SEMI_LAGRANGIAN == static_cast<int>(gust::WindAdvection::SemiLagrangian));
static_assert(GUST_ADVECTION_NONE == static_cast<int>(gust::WindAdvection::None));

static_assert(GUST_PRESSURE_MULTIGRID_PCG == static_cast<int>(gust::WindPressure::MultigridPCG));
static_assert(GUST_PRESSURE_MULTIGRID == static_cast<int>(gust::WindPressure::Multigrid));
static_assert(GUST_PRESSURE_JACOBI == static_cast<int>(gust::WindPressure::Jacobi));

static_assert(GUST_SUBMISSION_OWN_QUEUE == static_cast<int>(gust::Submission::OwnQueue));
static_assert(GUST_SUBMISSION_HOST_COMMANDS == static_cast<int>(gust::Submission::HostCommands));

static_assert(GUST_VOXELIZE_AUTO == static_cast<int>(gust::VoxelizePath::Auto));
static_assert(GUST_VOXELIZE_RASTER == static_cast<int>(gust::VoxelizePath::Raster));
static_assert(GUST_VOXELIZE_COMPUTE == static_cast<int>(gust::VoxelizePath::Compute));

static_assert(GUST_WIND_EMITTER_DIRECTIONAL == static_cast<int>(gust::WindEmitterType::Directional));
static_assert(GUST_WIND_EMITTER_OMNI == static_cast<int>(gust::WindEmitterType::Omni));
static_assert(GUST_WIND_EMITTER_VORTEX == static_cast<int>(gust::WindEmitterType::Vortex));
static_assert(GUST_WIND_EMITTER_CAPSULE_MOTOR == static_cast<int>(gust::WindEmitterType::CapsuleMotor));
static_assert(GUST_WIND_EMITTER_CONE_MOTOR == static_cast<int>(gust::WindEmitterType::ConeMotor));

static_assert(GUST_TREE_NODE_STALE == static_cast<int>(gust::TreeNodeState::Stale));
static_assert(GUST_TREE_NODE_REACHED == static_cast<int>(gust::TreeNodeState::Reached));
static_assert(GUST_TREE_NODE_STATIC == static_cast<int>(gust::TreeNodeState::Static));

// The conversions below copy these arrays element by element.
static_assert(sizeof(gust_wind_domain::cells) == sizeof(gust::WindDomain::cells));
static_assert(sizeof(gust_wind_texture::world_to_texture) == sizeof(gust::Mat4::m));
static_assert(sizeof(gust_wind_texture::extent) == sizeof(gust::WindTexture::extent));
static_assert(sizeof(gust_voxel_grid_info::resolution) == sizeof(gust::VoxelGridInfo::resolution));

namespace {

// Returned when even the message could not be stored.
constexpr const char* kNoMemoryForMessage = "out of host memory (while storing the error message)";

// The message of the last failure that had no live system to hold it (gust_last_create_error).
thread_local std::string t_message;
thread_local const char* t_message_ptr = "";

// One live system: the C hooks its gust::Hooks trampoline into, the System, and its last message.
struct Handle {
    gust_hooks hooks{};
    std::unique_ptr<gust::System> system;
    std::string message;
    const char* message_ptr = "";
};

// Live systems by handle value. Never destroyed, so a host may destroy systems from its own static
// destructors whatever their order.
struct Registry {
    std::mutex mutex;
    std::unordered_map<std::uintptr_t, Handle*> live;
    std::uintptr_t next = 1;
};

Registry& registry() {
    static Registry* instance = new Registry;
    return *instance;
}

Handle* find(gust_system system) {
    if (!system) return nullptr;
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto it = r.live.find(reinterpret_cast<std::uintptr_t>(system));
    return it == r.live.end() ? nullptr : it->second;
}

// Stores "function: message" in `target`, pointing `ptr` at it (or at a static text if that fails).
void store_message(std::string& target, const char*& ptr, std::string_view function,
                   std::string_view message) noexcept {
    try {
        target.assign(function);
        target += ": ";
        target += message.empty() ? std::string_view("failed without a message") : message;
        ptr = target.c_str();
    } catch (...) {
        ptr = kNoMemoryForMessage;
    }
}

gust_result fail_thread(gust_result code, std::string_view function, std::string_view message) noexcept {
    store_message(t_message, t_message_ptr, function, message);
    return code;
}

gust_result to_result(gust::ErrorCode code) {
    return static_cast<gust_result>(static_cast<std::int32_t>(code));
}

gust::Outcome invalid(std::string message) {
    return {gust::ErrorCode::InvalidArgument, std::move(message)};
}

// The result of an exception that reached the C boundary: gust itself does not throw, so this is host memory
// running out in the copies made here, or a bug.
std::pair<gust_result, std::string> from_exception() noexcept {
    try {
        throw;
    } catch (const std::bad_alloc&) {
        return {GUST_ERROR_DEVICE_FAILURE, "out of host memory"};
    } catch (const std::exception& e) {
        try {
            return {GUST_ERROR_DEVICE_FAILURE, std::string("internal error: ") + e.what()};
        } catch (...) {
            return {GUST_ERROR_DEVICE_FAILURE, {}};
        }
    } catch (...) {
        return {GUST_ERROR_DEVICE_FAILURE, {}};
    }
}

// Runs `body(System&)` -> gust::Outcome on a live system, keeping a failure's message in the system.
template <class Body>
gust_result on_system(gust_system system, std::string_view function, Body&& body) noexcept {
    Handle* handle = nullptr;
    try {
        handle = find(system);
        if (!handle) {
            return fail_thread(GUST_ERROR_INVALID_HANDLE, function,
                               system ? "system is not alive (destroyed, or not from gust_system_create)"
                                      : "system is NULL");
        }
        gust::Outcome outcome = body(*handle->system);
        if (outcome) return GUST_OK;
        store_message(handle->message, handle->message_ptr, function, outcome.message());
        return to_result(outcome.code());
    } catch (...) {
        auto [code, message] = from_exception();
        if (handle) {
            store_message(handle->message, handle->message_ptr, function, message);
            return code;
        }
        return fail_thread(code, function, message);
    }
}

// Runs `body()` -> gust::Outcome for a call without a system, keeping a failure's message per thread.
template <class Body> gust_result on_thread(std::string_view function, Body&& body) noexcept {
    try {
        gust::Outcome outcome = body();
        if (outcome) return GUST_OK;
        return fail_thread(to_result(outcome.code()), function, outcome.message());
    } catch (...) {
        auto [code, message] = from_exception();
        return fail_thread(code, function, message);
    }
}

bool same_major_minor(std::uint32_t header_version) {
    return (header_version >> 12) == (gust::kHeaderVersion >> 12);
}

std::string version_string(std::uint32_t v) {
    return std::to_string(v >> 22) + "." + std::to_string((v >> 12) & 0x3ffu) + "." +
           std::to_string(v & 0xfffu);
}

gust::Outcome version_mismatch(std::uint32_t header_version) {
    return {gust::ErrorCode::VersionMismatch, "header_version " + version_string(header_version) +
                                                  " differs from the library's " +
                                                  version_string(gust::kHeaderVersion) +
                                                  " in major or minor: rebuild against the library's gust.h"};
}

// Trampolines from gust::Hooks to the C hooks; `user` is the Handle's gust_hooks.
void* hook_allocate(void* user, std::size_t bytes, std::size_t alignment) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    return hooks->allocate(hooks->user, bytes, alignment);
}
void hook_free(void* user, void* memory) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    hooks->free(hooks->user, memory);
}
void hook_log(void* user, gust::LogLevel level, const char* message) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    hooks->log(hooks->user, static_cast<gust_log_level>(static_cast<std::int32_t>(level)), message);
}
void hook_assert_failed(void* user, const char* expression, const char* file, int line) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    hooks->assert_failed(hooks->user, expression, file, line);
}

// Destroys a Handle and gives its memory back to whoever allocated it (the host's allocate hook or new).
struct HandleDeleter {
    void operator()(Handle* handle) const {
        const gust_hooks hooks = handle->hooks;
        if (hooks.allocate) {
            handle->~Handle();
            hooks.free(hooks.user, handle);
        } else {
            delete handle;
        }
    }
};
using HandlePtr = std::unique_ptr<Handle, HandleDeleter>;

// A Handle in the host's memory when it gave an allocate hook (null if that returned null).
HandlePtr new_handle(const gust_hooks& hooks) {
    if (!hooks.allocate) {
        auto handle = HandlePtr(new Handle);
        handle->hooks = hooks;
        return handle;
    }
    void* memory = hooks.allocate(hooks.user, sizeof(Handle), alignof(Handle));
    if (!memory) return nullptr;
    auto handle = HandlePtr(new (memory) Handle);
    handle->hooks = hooks;
    return handle;
}

// What the conversion itself relies on; System::create checks the rest.
gust::Outcome check_desc(const gust_system_desc& d) {
    // Before anything else is read: another version's struct may have another layout (header_version stays
    // the first field in every version).
    if (!same_major_minor(d.header_version)) return version_mismatch(d.header_version);
    // The Handle itself is allocated with the hooks, before System::create checks them.
    if (d.hooks.allocate && !d.hooks.free)
        return invalid("desc->hooks.allocate is set but hooks.free is NULL");
    if (d.host && d.host->enabled_extension_count > 0 && !d.host->enabled_extensions) {
        return invalid("desc->host->enabled_extensions is NULL but enabled_extension_count is " +
                       std::to_string(d.host->enabled_extension_count));
    }
    return {};
}

// Conversions between the C structs and the C++ ones. Each C++ struct is taken apart with a structured
// binding that names every field, so when gust.hpp gains or loses a field this stops compiling until gust.h
// mirrors the change.

// A C enum field may hold any int the caller stored; loading it as the C enum type is undefined in C++ when
// the value is no enumerator, so its bytes are copied into an int32_t and the C++ side checks the value.
template <class CppEnum, class CEnum> CppEnum to_cpp_enum(const CEnum& c) {
    static_assert(sizeof(CEnum) == sizeof(std::int32_t));
    std::int32_t raw = 0;
    std::memcpy(&raw, &c, sizeof raw);
    return static_cast<CppEnum>(raw);
}

gust::Vec3 to_cpp(const gust_vec3& v) {
    return {v.x, v.y, v.z};
}
gust_vec3 to_c(const gust::Vec3& v) {
    return {v.x, v.y, v.z};
}

gust::Mat4 to_cpp_matrix(const float* m) {
    gust::Mat4 out;
    std::copy_n(m, 16, out.m);
    return out;
}

gust::Hooks to_cpp(gust_hooks& c) {
    gust::Hooks out;
    auto& [user, allocate, release, log_message, assert_failed] = out;
    user = &c;
    if (c.allocate) allocate = hook_allocate;
    if (c.free) release = hook_free;
    if (c.log) log_message = hook_log;
    if (c.assert_failed) assert_failed = hook_assert_failed;
    return out;
}

gust::HostDevice to_cpp(const gust_host_device& c) {
    gust::HostDevice out;
    auto& [instance, physical_device, device, queue_family, queue_index, get_instance_proc_addr,
           get_device_proc_addr, enabled_extensions, debug_utils] = out;
    instance = c.instance;
    physical_device = c.physical_device;
    device = c.device;
    queue_family = c.queue_family;
    queue_index = c.queue_index;
    get_instance_proc_addr = c.get_instance_proc_addr;
    get_device_proc_addr = c.get_device_proc_addr;
    if (c.enabled_extension_count > 0) enabled_extensions = {c.enabled_extensions, c.enabled_extension_count};
    debug_utils = c.debug_utils;
    return out;
}

gust::WindDomain to_cpp(const gust_wind_domain& c) {
    gust::WindDomain out;
    auto& [cells, cell_size, voxels_per_cell, branching, focus, hysteresis] = out;
    std::copy_n(c.cells, 3, cells);
    cell_size = c.cell_size;
    voxels_per_cell = c.voxels_per_cell;
    branching = c.branching;
    focus = to_cpp(c.focus);
    hysteresis = c.hysteresis;
    return out;
}
gust_wind_domain to_c(const gust::WindDomain& d) {
    const auto& [cells, cell_size, voxels_per_cell, branching, focus, hysteresis] = d;
    return {.cells = {cells[0], cells[1], cells[2]},
            .cell_size = cell_size,
            .voxels_per_cell = voxels_per_cell,
            .branching = branching,
            .focus = to_c(focus),
            .hysteresis = hysteresis};
}

// The advection and the pressure solver are passed on unchecked: System::create rejects unknown ones.
gust::WindSettings to_cpp(const gust_wind_settings& c) {
    gust::WindSettings out;
    auto& [tolerance, max_cycles, vorticity, viscosity, advection, max_solid_speed, cycles_per_step, pressure,
           max_iterations] = out;
    tolerance = c.tolerance;
    max_cycles = c.max_cycles;
    vorticity = c.vorticity;
    viscosity = c.viscosity;
    advection = to_cpp_enum<gust::WindAdvection>(c.advection);
    max_solid_speed = c.max_solid_speed;
    cycles_per_step = c.cycles_per_step;
    pressure = to_cpp_enum<gust::WindPressure>(c.pressure);
    max_iterations = c.max_iterations;
    return out;
}
gust_wind_settings to_c(const gust::WindSettings& w) {
    const auto& [tolerance, max_cycles, vorticity, viscosity, advection, max_solid_speed, cycles_per_step,
                 pressure, max_iterations] = w;
    return {.tolerance = tolerance,
            .max_cycles = max_cycles,
            .vorticity = vorticity,
            .viscosity = viscosity,
            .advection = static_cast<gust_advection>(static_cast<std::int32_t>(advection)),
            .max_solid_speed = max_solid_speed,
            .cycles_per_step = cycles_per_step,
            .pressure = static_cast<gust_pressure>(static_cast<std::int32_t>(pressure)),
            .max_iterations = max_iterations};
}

// `host_device` is the converted c.host (or null); the hooks trampoline into `hooks_in_handle`.
gust::SystemDesc to_cpp(const gust_system_desc& c, const gust::HostDevice* host_device,
                        gust_hooks& hooks_in_handle) {
    gust::SystemDesc out;
    auto& [header_version, host, validation, device, submission, frames_in_flight, voxelize, domain, wind,
           hooks, pipeline_cache] = out;
    header_version = c.header_version;
    host = host_device;
    validation = c.validation;
    device = c.device;
    submission = to_cpp_enum<gust::Submission>(c.submission);
    frames_in_flight = c.frames_in_flight;
    voxelize = to_cpp_enum<gust::VoxelizePath>(c.voxelize);
    domain = to_cpp(c.domain);
    wind = to_cpp(c.wind);
    hooks = to_cpp(hooks_in_handle);
    pipeline_cache = c.pipeline_cache;
    return out;
}
// The defaults: no host device and no hooks, whatever the C++ ones hold.
gust_system_desc to_c(const gust::SystemDesc& d, std::uint32_t header_version) {
    const auto& [version, host, validation, device, submission, frames_in_flight, voxelize, domain, wind,
                 hooks, pipeline_cache] = d;
    return {.header_version = header_version,
            .host = nullptr,
            .validation = validation,
            .device = device,
            .submission = static_cast<gust_submission>(static_cast<std::int32_t>(submission)),
            .frames_in_flight = frames_in_flight,
            .voxelize = static_cast<gust_voxelize_path>(static_cast<std::int32_t>(voxelize)),
            .domain = to_c(domain),
            .wind = to_c(wind),
            .hooks = {},
            .pipeline_cache = pipeline_cache};
}

gust::MeshDesc to_cpp(const gust_mesh_desc& c) {
    gust::MeshDesc out;
    auto& [positions, vertex_count, stride, indices, index_count, deforming] = out;
    positions = c.positions;
    vertex_count = c.vertex_count;
    stride = c.stride;
    indices = c.indices;
    index_count = c.index_count;
    deforming = c.deforming;
    return out;
}
gust_mesh_desc to_c(const gust::MeshDesc& m) {
    const auto& [positions, vertex_count, stride, indices, index_count, deforming] = m;
    return {.positions = positions,
            .vertex_count = vertex_count,
            .stride = stride,
            .indices = indices,
            .index_count = index_count,
            .deforming = deforming};
}

// The type is passed on unchecked: System::set_emitters rejects unknown ones.
gust::WindEmitter to_cpp(const gust_wind_emitter& c) {
    gust::WindEmitter out;
    auto& [type, position, direction, radius, strength, falloff, length] = out;
    type = to_cpp_enum<gust::WindEmitterType>(c.type);
    position = to_cpp(c.position);
    direction = to_cpp(c.direction);
    radius = c.radius;
    strength = c.strength;
    falloff = c.falloff;
    length = c.length;
    return out;
}
gust_wind_emitter to_c(const gust::WindEmitter& e) {
    const auto& [type, position, direction, radius, strength, falloff, length] = e;
    return {.type = static_cast<gust_wind_emitter_type>(static_cast<std::int32_t>(type)),
            .position = to_c(position),
            .direction = to_c(direction),
            .radius = radius,
            .strength = strength,
            .falloff = falloff,
            .length = length};
}

gust_wind_sample to_c(const gust::WindSample& s) {
    const auto& [direction, speed, gust_speed] = s;
    return {.direction = to_c(direction), .speed = speed, .gust = gust_speed};
}

gust_wind_texture to_c(const gust::WindTexture& t) {
    const auto& [image, view, sampler, format, extent, world_to_texture, layout, frame] = t;
    gust_wind_texture out{.image = image, .view = view, .sampler = sampler, .format = format};
    std::copy_n(extent, 3, out.extent);
    std::copy_n(world_to_texture.m, 16, out.world_to_texture);
    out.layout = layout;
    out.frame = frame;
    return out;
}

// The per-pass times stay in the C++ stats (gust_system_stats_pass reads them there).
gust_frame_stats to_c(const gust::FrameStats& f) {
    const auto& [frame, fragments, voxels, nodes, refined, coarsened, pool_bytes, fragment_bytes, dense_bytes,
                 divergence_before, divergence_after, residual, cycles, converged, diverged, sealed_cells,
                 rejected_triangles, dispatches, submissions, waits, cut_cells, fluid_cells, free_node_blocks,
                 free_mask_blocks, exhausted, pool_growths, static_rebuilt, nodes_per_level, ms] = f;
    return {.frame = frame,
            .fragments = fragments,
            .voxels = voxels,
            .nodes = nodes,
            .refined = refined,
            .coarsened = coarsened,
            .pool_bytes = pool_bytes,
            .fragment_bytes = fragment_bytes,
            .dense_bytes = dense_bytes,
            .divergence_before = divergence_before,
            .divergence_after = divergence_after,
            .residual = residual,
            .cycles = cycles,
            .sealed_cells = sealed_cells,
            .rejected_triangles = rejected_triangles,
            .dispatches = dispatches,
            .submissions = submissions,
            .waits = waits,
            .cut_cells = cut_cells,
            .fluid_cells = fluid_cells,
            .free_node_blocks = free_node_blocks,
            .free_mask_blocks = free_mask_blocks,
            .exhausted = exhausted,
            .pool_growths = pool_growths,
            .converged = converged,
            .diverged = diverged,
            .static_rebuilt = static_rebuilt};
}

std::vector<gust::Vec3> to_cpp(const gust_vec3* points, std::size_t count) {
    std::vector<gust::Vec3> out(count);
    for (std::size_t i = 0; i < count; ++i)
        out[i] = to_cpp(points[i]);
    return out;
}

void to_c(const std::vector<gust::Vec3>& in, gust_vec3* out) {
    for (std::size_t i = 0; i < in.size(); ++i)
        out[i] = to_c(in[i]);
}

const gust::DeviceRequirements& static_requirements() {
    static const gust::DeviceRequirements requirements = gust::device_requirements();
    return requirements;
}

std::uint32_t count32(std::size_t n) {
    return static_cast<std::uint32_t>(n);
}

/// A debug call that fills a list of C++ entries, run for a C array of `capacity` entries: the call
/// writes into a list of its own type and `convert` turns each of the first min(capacity, total) into a
/// C entry, which keeps the C and C++ structs free to differ at the cost of a copy (these are debug
/// calls). `*count` receives the total, as the C++ call's count does.
template <class Entry, class CEntry, class Call, class Convert>
gust::Outcome fill_list(CEntry* out, std::size_t capacity, std::size_t* count, const char* name, Call call,
                        Convert convert) {
    if (!count) return invalid("count (the output) is NULL");
    *count = 0;
    if (capacity > 0 && !out)
        return invalid(std::string(name) + " is NULL but capacity is " + std::to_string(capacity));
    std::vector<Entry> list(capacity);
    std::size_t total = 0;
    if (gust::Outcome outcome = call(std::span<Entry>(list), total); !outcome) return outcome;
    for (std::size_t i = 0; i < std::min(capacity, total); ++i)
        out[i] = convert(list[i]);
    *count = total;
    return {};
}

} // namespace

extern "C" {

uint32_t gust_library_version(void) {
    return gust::library_version();
}

const char* gust_last_create_error(void) {
    return t_message_ptr;
}

gust_result gust_get_device_requirements(gust_device_requirements* requirements) {
    return on_thread("gust_get_device_requirements", [&]() -> gust::Outcome {
        if (!requirements) return invalid("requirements is NULL");
        const auto& [api_version, extensions, optional_extensions, features] = static_requirements();
        *requirements = {.api_version = api_version,
                         .extension_count = count32(extensions.size()),
                         .extensions = extensions.data(),
                         .optional_extension_count = count32(optional_extensions.size()),
                         .optional_extensions = optional_extensions.data(),
                         .feature_count = count32(features.size()),
                         .features = features.data()};
        return {};
    });
}

gust_result gust_add_required_features(VkPhysicalDeviceFeatures2* features) {
    return on_thread("gust_add_required_features", [&]() -> gust::Outcome {
        if (!features) return invalid("features is NULL");
        return gust::add_required_features(*features);
    });
}

gust_result gust_system_desc_init(gust_system_desc* desc, uint32_t header_version) {
    return on_thread("gust_system_desc_init", [&]() -> gust::Outcome {
        if (!desc) return invalid("desc is NULL");
        // The first field is the same in every version, so it is safe to write even on a mismatch, and
        // gust_system_create then names the mismatch too.
        desc->header_version = header_version;
        if (!same_major_minor(header_version)) return version_mismatch(header_version);
        *desc = to_c(gust::SystemDesc{}, header_version);
        return {};
    });
}

gust_result gust_mesh_desc_defaults(gust_mesh_desc* desc) {
    return on_thread("gust_mesh_desc_defaults", [&]() -> gust::Outcome {
        if (!desc) return invalid("desc is NULL");
        *desc = to_c(gust::MeshDesc{});
        return {};
    });
}

gust_result gust_wind_emitter_defaults(gust_wind_emitter* emitter) {
    return on_thread("gust_wind_emitter_defaults", [&]() -> gust::Outcome {
        if (!emitter) return invalid("emitter is NULL");
        *emitter = to_c(gust::WindEmitter{});
        return {};
    });
}

gust_result gust_system_create(const gust_system_desc* desc, gust_system* system) {
    return on_thread("gust_system_create", [&]() -> gust::Outcome {
        if (!system) return invalid("system (the output) is NULL");
        *system = nullptr;
        if (!desc) return invalid("desc is NULL");
        if (gust::Outcome outcome = check_desc(*desc); !outcome) return outcome;

        HandlePtr handle = new_handle(desc->hooks);
        if (!handle) return {gust::ErrorCode::DeviceFailure, "hooks.allocate returned NULL for the system"};
        gust::HostDevice host;
        if (desc->host) host = to_cpp(*desc->host);
        const gust::SystemDesc d = to_cpp(*desc, desc->host ? &host : nullptr, handle->hooks);
        if (gust::Outcome outcome = gust::System::create(d, handle->system); !outcome) return outcome;

        Registry& r = registry();
        std::lock_guard lock(r.mutex);
        const std::uintptr_t id = r.next;
        r.live.emplace(id, handle.get());
        ++r.next;
        handle.release();
        *system = reinterpret_cast<gust_system>(id);
        return {};
    });
}

gust_result gust_system_destroy(gust_system system) {
    try {
        Handle* handle = nullptr;
        {
            Registry& r = registry();
            std::lock_guard lock(r.mutex);
            auto it = system ? r.live.find(reinterpret_cast<std::uintptr_t>(system)) : r.live.end();
            if (it != r.live.end()) {
                handle = it->second;
                r.live.erase(it);
            }
        }
        if (!handle) {
            return fail_thread(GUST_ERROR_INVALID_HANDLE, "gust_system_destroy",
                               system ? "system is not alive (destroyed, or not from gust_system_create)"
                                      : "system is NULL");
        }
        HandleDeleter{}(handle);
        return GUST_OK;
    } catch (...) {
        auto [code, message] = from_exception();
        return fail_thread(code, "gust_system_destroy", message);
    }
}

const char* gust_system_last_error(gust_system system) {
    try {
        Handle* handle = find(system);
        return handle ? handle->message_ptr : t_message_ptr;
    } catch (...) {
        return "gust_system_last_error: the registry of systems could not be locked";
    }
}

gust_result gust_system_create_mesh(gust_system system, const gust_mesh_desc* desc, gust_mesh* mesh) {
    return on_system(system, "gust_system_create_mesh", [&](gust::System& s) -> gust::Outcome {
        if (!mesh) return invalid("mesh (the output) is NULL");
        *mesh = 0;
        if (!desc) return invalid("desc is NULL");
        gust::MeshId id = 0;
        gust::Outcome outcome = s.create_mesh(to_cpp(*desc), id);
        if (outcome) *mesh = id;
        return outcome;
    });
}

gust_result gust_system_destroy_mesh(gust_system system, gust_mesh mesh) {
    return on_system(system, "gust_system_destroy_mesh",
                     [&](gust::System& s) { return s.destroy_mesh(mesh); });
}

gust_result gust_system_set_vertices(gust_system system, gust_mesh mesh, const float* positions,
                                     uint32_t vertex_count, uint32_t stride, bool teleport) {
    return on_system(system, "gust_system_set_vertices", [&](gust::System& s) {
        return s.set_vertices(mesh, positions, vertex_count, stride, teleport);
    });
}

gust_result gust_system_set_vertices_buffer(gust_system system, gust_mesh mesh, VkBuffer buffer,
                                            VkDeviceSize offset, uint32_t vertex_count, bool teleport) {
    return on_system(system, "gust_system_set_vertices_buffer", [&](gust::System& s) {
        return s.set_vertices(mesh, buffer, offset, vertex_count, teleport);
    });
}

gust_result gust_system_create_instance(gust_system system, gust_mesh mesh, const float transform[16],
                                        bool moving, gust_instance* instance) {
    return on_system(system, "gust_system_create_instance", [&](gust::System& s) -> gust::Outcome {
        if (!instance) return invalid("instance (the output) is NULL");
        *instance = 0;
        if (!transform) return invalid("transform is NULL");
        gust::InstanceId id = 0;
        gust::Outcome outcome = s.create_instance(mesh, to_cpp_matrix(transform), moving, id);
        if (outcome) *instance = id;
        return outcome;
    });
}

gust_result gust_system_create_moving_instance(gust_system system, gust_mesh mesh, const float transform[16],
                                               const float previous[16], gust_instance* instance) {
    return on_system(system, "gust_system_create_moving_instance", [&](gust::System& s) -> gust::Outcome {
        if (!instance) return invalid("instance (the output) is NULL");
        *instance = 0;
        if (!transform) return invalid("transform is NULL");
        if (!previous) return invalid("previous is NULL");
        gust::InstanceId id = 0;
        gust::Outcome outcome =
            s.create_moving_instance(mesh, to_cpp_matrix(transform), to_cpp_matrix(previous), id);
        if (outcome) *instance = id;
        return outcome;
    });
}

gust_result gust_system_set_transform(gust_system system, gust_instance instance, const float transform[16],
                                      bool teleport) {
    return on_system(system, "gust_system_set_transform", [&](gust::System& s) -> gust::Outcome {
        if (!transform) return invalid("transform is NULL");
        return s.set_transform(instance, to_cpp_matrix(transform), teleport);
    });
}

gust_result gust_system_destroy_instance(gust_system system, gust_instance instance) {
    return on_system(system, "gust_system_destroy_instance",
                     [&](gust::System& s) { return s.destroy_instance(instance); });
}

gust_result gust_system_set_emitters(gust_system system, const gust_wind_emitter* emitters, size_t count) {
    return on_system(system, "gust_system_set_emitters", [&](gust::System& s) -> gust::Outcome {
        if (count > GUST_MAX_EMITTERS) {
            return invalid("count is " + std::to_string(count) + ", more than GUST_MAX_EMITTERS (" +
                           std::to_string(GUST_MAX_EMITTERS) + ")");
        }
        if (!emitters && count > 0) return invalid("emitters is NULL but count is " + std::to_string(count));
        std::vector<gust::WindEmitter> converted(count);
        for (std::size_t i = 0; i < count; ++i)
            converted[i] = to_cpp(emitters[i]);
        return s.set_emitters(converted);
    });
}

gust_result gust_system_set_ambient(gust_system system, gust_vec3 velocity) {
    return on_system(system, "gust_system_set_ambient",
                     [&](gust::System& s) { return s.set_ambient(to_cpp(velocity)); });
}

gust_result gust_system_set_focus(gust_system system, gust_vec3 position) {
    return on_system(system, "gust_system_set_focus",
                     [&](gust::System& s) { return s.set_focus(to_cpp(position)); });
}

gust_result gust_system_step(gust_system system, float dt) {
    return on_system(system, "gust_system_step", [&](gust::System& s) { return s.step(dt); });
}

gust_result gust_system_step_commands(gust_system system, float dt, VkCommandBuffer commands) {
    return on_system(system, "gust_system_step_commands",
                     [&](gust::System& s) { return s.step(dt, commands); });
}

gust_result gust_system_query(gust_system system, const gust_vec3* points, size_t count,
                              gust_vec3* velocities) {
    return on_system(system, "gust_system_query", [&](gust::System& s) -> gust::Outcome {
        if (count > 0 && !points) return invalid("points is NULL but count is " + std::to_string(count));
        if (count > 0 && !velocities)
            return invalid("velocities is NULL but count is " + std::to_string(count));
        if (count > gust::kMaxQueryPoints)
            return invalid(std::to_string(count) + " points, more than GUST_MAX_QUERY_POINTS");
        const std::vector<gust::Vec3> in = to_cpp(points, count);
        std::vector<gust::Vec3> out(count);
        gust::Outcome outcome = s.query(in, out);
        if (outcome) to_c(out, velocities);
        return outcome;
    });
}

gust_result gust_system_query_async(gust_system system, const gust_vec3* points, size_t count,
                                    gust_query* query) {
    return on_system(system, "gust_system_query_async", [&](gust::System& s) -> gust::Outcome {
        if (!query) return invalid("query (the output) is NULL");
        *query = 0;
        if (count > 0 && !points) return invalid("points is NULL but count is " + std::to_string(count));
        if (count > gust::kMaxQueryPoints)
            return invalid(std::to_string(count) + " points, more than GUST_MAX_QUERY_POINTS");
        const std::vector<gust::Vec3> in = to_cpp(points, count);
        gust::QueryId id = 0;
        gust::Outcome outcome = s.query_async(in, id);
        if (outcome) *query = id;
        return outcome;
    });
}

gust_result gust_system_fetch(gust_system system, gust_query query, gust_vec3* velocities, size_t count) {
    return on_system(system, "gust_system_fetch", [&](gust::System& s) -> gust::Outcome {
        if (count > 0 && !velocities)
            return invalid("velocities is NULL but count is " + std::to_string(count));
        std::vector<gust::Vec3> out(count);
        gust::Outcome outcome = s.fetch(query, out);
        if (outcome) to_c(out, velocities);
        return outcome;
    });
}

gust_result gust_system_wind_at(gust_system system, gust_vec3 point, gust_wind_sample* sample) {
    return on_system(system, "gust_system_wind_at", [&](gust::System& s) -> gust::Outcome {
        if (!sample) return invalid("sample (the output) is NULL");
        gust::WindSample w;
        gust::Outcome outcome = s.wind_at(to_cpp(point), w);
        if (outcome) *sample = to_c(w);
        return outcome;
    });
}

gust_result gust_system_wind_texture(gust_system system, gust_wind_texture* texture) {
    return on_system(system, "gust_system_wind_texture", [&](gust::System& s) -> gust::Outcome {
        if (!texture) return invalid("texture (the output) is NULL");
        *texture = to_c(s.wind_texture());
        return {};
    });
}

gust_result gust_system_stats(gust_system system, gust_frame_stats* stats) {
    return on_system(system, "gust_system_stats", [&](gust::System& s) -> gust::Outcome {
        if (!stats) return invalid("stats (the output) is NULL");
        *stats = to_c(s.stats());
        return {};
    });
}

gust_result gust_system_stats_nodes_per_level(gust_system system, uint64_t* nodes, uint32_t capacity,
                                              uint32_t* count) {
    return on_system(system, "gust_system_stats_nodes_per_level", [&](gust::System& s) -> gust::Outcome {
        if (!count) return invalid("count (the output) is NULL");
        if (!nodes && capacity > 0)
            return invalid("nodes is NULL but capacity is " + std::to_string(capacity));
        const auto& levels = s.stats().nodes_per_level;
        *count = count32(levels.size());
        std::copy_n(levels.begin(), std::min<std::size_t>(capacity, levels.size()), nodes);
        return {};
    });
}

gust_result gust_system_stats_pass_count(gust_system system, uint32_t* count) {
    return on_system(system, "gust_system_stats_pass_count", [&](gust::System& s) -> gust::Outcome {
        if (!count) return invalid("count (the output) is NULL");
        *count = count32(s.stats().ms.size());
        return {};
    });
}

gust_result gust_system_stats_pass(gust_system system, uint32_t index, const char** name, double* ms) {
    return on_system(system, "gust_system_stats_pass", [&](gust::System& s) -> gust::Outcome {
        const auto& passes = s.stats().ms;
        if (index >= passes.size()) {
            return invalid("index " + std::to_string(index) + " out of range (" +
                           std::to_string(passes.size()) + " passes)");
        }
        if (name) *name = passes[index].first.c_str();
        if (ms) *ms = passes[index].second;
        return {};
    });
}

gust_result gust_system_domain_origin(gust_system system, gust_vec3* origin) {
    return on_system(system, "gust_system_domain_origin", [&](gust::System& s) -> gust::Outcome {
        if (!origin) return invalid("origin (the output) is NULL");
        *origin = to_c(s.domain_origin());
        return {};
    });
}

gust_result gust_system_device_name(gust_system system, const char** name) {
    return on_system(system, "gust_system_device_name", [&](gust::System& s) -> gust::Outcome {
        if (!name) return invalid("name (the output) is NULL");
        *name = s.device_name();
        return {};
    });
}

gust_result gust_system_export_vdb(gust_system system, const char* path) {
    return on_system(system, "gust_system_export_vdb", [&](gust::System& s) { return s.export_vdb(path); });
}

gust_result gust_system_debug_voxel_grid(gust_system system, gust_voxel_grid_info* info) {
    return on_system(system, "gust_system_debug_voxel_grid", [&](gust::System& s) -> gust::Outcome {
        if (!info) return invalid("info (the output) is NULL");
        gust::VoxelGridInfo grid;
        gust::Outcome outcome = s.debug_voxel_grid(grid);
        if (outcome) {
            info->origin = to_c(grid.origin);
            info->voxel_size = grid.voxel_size;
            std::copy_n(grid.resolution, 3, info->resolution);
            info->depth = grid.depth;
            info->branching = grid.branching;
        }
        return outcome;
    });
}

gust_result gust_system_debug_voxels(gust_system system, gust_voxel_coord* voxels, size_t capacity,
                                     size_t* count) {
    return on_system(system, "gust_system_debug_voxels", [&](gust::System& s) {
        return fill_list<gust::VoxelCoord>(
            voxels, capacity, count, "voxels",
            [&](std::span<gust::VoxelCoord> out, std::size_t& total) { return s.debug_voxels(out, total); },
            [](const gust::VoxelCoord& v) {
                return gust_voxel_coord{v.i, v.j, v.k};
            });
    });
}

gust_result gust_system_debug_tree_nodes(gust_system system, gust_tree_node* nodes, size_t capacity,
                                         size_t* count) {
    return on_system(system, "gust_system_debug_tree_nodes", [&](gust::System& s) {
        return fill_list<gust::TreeNode>(
            nodes, capacity, count, "nodes",
            [&](std::span<gust::TreeNode> out, std::size_t& total) { return s.debug_tree_nodes(out, total); },
            [](const gust::TreeNode& n) {
                return gust_tree_node{.min = to_c(n.min),
                                      .size = n.size,
                                      .level = n.level,
                                      .state = static_cast<gust_tree_node_state>(n.state),
                                      .refined = n.refined};
            });
    });
}

} // extern "C"
