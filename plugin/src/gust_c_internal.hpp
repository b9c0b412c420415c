// The C ABI's internals (gust_c.cpp, gust_c_answers.cpp): the registry of live systems, messages, the
// trampolines from gust::Hooks to the C hooks, and the conversions between the C structs and the C++ ones.
// Everything is inline, so the registry and the per-thread message exist once in the library.
#pragma once

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

namespace gust::capi {

// Returned when even the message could not be stored.
inline constexpr const char* kNoMemoryForMessage = "out of host memory (while storing the error message)";

// The message of the last failure that had no live system to hold it (gust_last_create_error).
inline thread_local std::string t_message;
inline thread_local const char* t_message_ptr = "";

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

inline Registry& registry() {
    static Registry* instance = new Registry;
    return *instance;
}

inline Handle* find(gust_system system) {
    if (!system) return nullptr;
    Registry& r = registry();
    std::lock_guard lock(r.mutex);
    auto it = r.live.find(reinterpret_cast<std::uintptr_t>(system));
    return it == r.live.end() ? nullptr : it->second;
}

// Stores "function: message" in `target`, pointing `ptr` at it (or at a static text if that fails).
inline void store_message(std::string& target, const char*& ptr, std::string_view function,
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

inline gust_result fail_thread(gust_result code, std::string_view function,
                               std::string_view message) noexcept {
    store_message(t_message, t_message_ptr, function, message);
    return code;
}

inline gust_result to_result(gust::ErrorCode code) {
    return static_cast<gust_result>(static_cast<std::int32_t>(code));
}

inline gust::Outcome invalid(std::string message) {
    return {gust::ErrorCode::InvalidArgument, std::move(message)};
}

// The result of an exception that reached the C boundary: gust itself does not throw, so this is host memory
// running out in the copies made here, or a bug.
inline std::pair<gust_result, std::string> from_exception() noexcept {
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
inline gust_result on_system(gust_system system, std::string_view function, Body&& body) noexcept {
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
        // The writer's message stays the writer's: a call refused as Busy keeps its own on its thread.
        if (outcome.code() == gust::ErrorCode::Busy)
            return fail_thread(to_result(outcome.code()), function, outcome.message());
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

// The same for a reader call (any thread, while another steps): a failure's message is kept per thread
// (gust_last_create_error), since the system's own belongs to its writer.
template <class Body>
inline gust_result on_system_reader(gust_system system, std::string_view function, Body&& body) noexcept {
    try {
        Handle* handle = find(system);
        if (!handle) {
            return fail_thread(GUST_ERROR_INVALID_HANDLE, function,
                               system ? "system is not alive (destroyed, or not from gust_system_create)"
                                      : "system is NULL");
        }
        gust::Outcome outcome = body(static_cast<const gust::System&>(*handle->system));
        if (outcome) return GUST_OK;
        return fail_thread(to_result(outcome.code()), function, outcome.message());
    } catch (...) {
        auto [code, message] = from_exception();
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

inline bool same_major_minor(std::uint32_t header_version) {
    return (header_version >> 12) == (gust::kHeaderVersion >> 12);
}

inline std::string version_string(std::uint32_t v) {
    return std::to_string(v >> 22) + "." + std::to_string((v >> 12) & 0x3ffu) + "." +
           std::to_string(v & 0xfffu);
}

inline gust::Outcome version_mismatch(std::uint32_t header_version) {
    return {gust::ErrorCode::VersionMismatch, "header_version " + version_string(header_version) +
                                                  " differs from the library's " +
                                                  version_string(gust::kHeaderVersion) +
                                                  " in major or minor: rebuild against the library's gust.h"};
}

// Trampolines from gust::Hooks to the C hooks; `user` is the Handle's gust_hooks.
inline void* hook_allocate(void* user, std::size_t bytes, std::size_t alignment) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    return hooks->allocate(hooks->user, bytes, alignment);
}
inline void hook_free(void* user, void* memory) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    hooks->free(hooks->user, memory);
}
inline void hook_log(void* user, gust::LogLevel level, const char* message) {
    const auto* hooks = static_cast<const gust_hooks*>(user);
    hooks->log(hooks->user, static_cast<gust_log_level>(static_cast<std::int32_t>(level)), message);
}
inline void hook_assert_failed(void* user, const char* expression, const char* file, int line) {
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
inline HandlePtr new_handle(const gust_hooks& hooks) {
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
inline gust::Outcome check_desc(const gust_system_desc& d) {
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

inline gust::Vec3 to_cpp(const gust_vec3& v) {
    return {v.x, v.y, v.z};
}
inline gust_vec3 to_c(const gust::Vec3& v) {
    return {v.x, v.y, v.z};
}

inline gust::Mat4 to_cpp_matrix(const float* m) {
    gust::Mat4 out;
    std::copy_n(m, 16, out.m);
    return out;
}

inline gust::Hooks to_cpp(gust_hooks& c) {
    gust::Hooks out;
    auto& [user, allocate, release, log_message, assert_failed] = out;
    user = &c;
    if (c.allocate) allocate = hook_allocate;
    if (c.free) release = hook_free;
    if (c.log) log_message = hook_log;
    if (c.assert_failed) assert_failed = hook_assert_failed;
    return out;
}

inline gust::HostDevice to_cpp(const gust_host_device& c) {
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

inline gust::WindDomain to_cpp(const gust_wind_domain& c) {
    gust::WindDomain out;
    auto& [cells, cell_size, voxels_per_cell, branching, focus, hysteresis, cascades, ratio] = out;
    std::copy_n(c.cells, 3, cells);
    cell_size = c.cell_size;
    voxels_per_cell = c.voxels_per_cell;
    branching = c.branching;
    focus = to_cpp(c.focus);
    hysteresis = c.hysteresis;
    cascades = c.cascades;
    ratio = c.ratio;
    return out;
}
inline gust_wind_domain to_c(const gust::WindDomain& d) {
    const auto& [cells, cell_size, voxels_per_cell, branching, focus, hysteresis, cascades, ratio] = d;
    return {.cells = {cells[0], cells[1], cells[2]},
            .cell_size = cell_size,
            .voxels_per_cell = voxels_per_cell,
            .branching = branching,
            .focus = to_c(focus),
            .hysteresis = hysteresis,
            .cascades = cascades,
            .ratio = ratio};
}

// The advection and the pressure solver are passed on unchecked: System::create rejects unknown ones.
inline gust::WindSettings to_cpp(const gust_wind_settings& c) {
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
inline gust_wind_settings to_c(const gust::WindSettings& w) {
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
inline gust::SystemDesc to_cpp(const gust_system_desc& c, const gust::HostDevice* host_device,
                               gust_hooks& hooks_in_handle) {
    gust::SystemDesc out;
    auto& [header_version, host, validation, device, submission, frames_in_flight, voxelize, domain, wind,
           hooks, pipeline_cache, snapshot, device_uuid, exported_copies] = out;
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
    snapshot = c.snapshot;
    device_uuid = c.device_uuid;
    exported_copies = c.exported_copies;
    return out;
}
// The defaults: no host device and no hooks, whatever the C++ ones hold.
inline gust_system_desc to_c(const gust::SystemDesc& d, std::uint32_t header_version) {
    const auto& [version, host, validation, device, submission, frames_in_flight, voxelize, domain, wind,
                 hooks, pipeline_cache, snapshot, device_uuid, exported_copies] = d;
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
            .pipeline_cache = pipeline_cache,
            .snapshot = snapshot,
            .device_uuid = device_uuid,
            .exported_copies = exported_copies};
}

inline gust::MeshSkin to_cpp(const gust_mesh_skin& c) {
    gust::MeshSkin out;
    auto& [joint_count, joints, weights] = out;
    joint_count = c.joint_count;
    joints = c.joints;
    weights = c.weights;
    return out;
}
/// `skin` receives the C skin's copy when there is one, and the result points at it.
inline gust::MeshDesc to_cpp(const gust_mesh_desc& c, gust::MeshSkin& skin) {
    gust::MeshDesc out;
    auto& [positions, vertex_count, stride, indices, index_count, deforming, skin_pointer] = out;
    positions = c.positions;
    vertex_count = c.vertex_count;
    stride = c.stride;
    indices = c.indices;
    index_count = c.index_count;
    deforming = c.deforming;
    if (c.skin) {
        skin = to_cpp(*c.skin);
        skin_pointer = &skin;
    }
    return out;
}
/// A MeshDesc's fields; its skin is not carried over (the defaults have none).
inline gust_mesh_desc to_c(const gust::MeshDesc& m) {
    const auto& [positions, vertex_count, stride, indices, index_count, deforming, skin] = m;
    static_cast<void>(skin);
    return {.positions = positions,
            .vertex_count = vertex_count,
            .stride = stride,
            .indices = indices,
            .index_count = index_count,
            .deforming = deforming,
            .skin = nullptr};
}

// The type is passed on unchecked: System::set_emitters rejects unknown ones.
inline gust::WindEmitter to_cpp(const gust_wind_emitter& c) {
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
inline gust_wind_emitter to_c(const gust::WindEmitter& e) {
    const auto& [type, position, direction, radius, strength, falloff, length] = e;
    return {.type = static_cast<gust_wind_emitter_type>(static_cast<std::int32_t>(type)),
            .position = to_c(position),
            .direction = to_c(direction),
            .radius = radius,
            .strength = strength,
            .falloff = falloff,
            .length = length};
}

inline gust_wind_sample to_c(const gust::WindSample& s) {
    const auto& [direction, speed, gust_speed] = s;
    return {.direction = to_c(direction), .speed = speed, .gust = gust_speed};
}

inline gust_wind_texture to_c(const gust::WindTexture& t) {
    const auto& [image, view, sampler, format, extent, world_to_texture, layout, frame] = t;
    gust_wind_texture out{.image = image, .view = view, .sampler = sampler, .format = format};
    std::copy_n(extent, 3, out.extent);
    std::copy_n(world_to_texture.m, 16, out.world_to_texture);
    out.layout = layout;
    out.frame = frame;
    return out;
}

// The per-pass times stay in the C++ stats (gust_system_stats_pass reads them there).
inline gust_frame_stats to_c(const gust::FrameStats& f) {
    const auto& [frame, fragments, voxels, nodes, refined, coarsened, pool_bytes, fragment_bytes, dense_bytes,
                 divergence_before, divergence_after, residual, cycles, converged, diverged, sealed_cells,
                 rejected_triangles, dispatches, stages, submissions, waits, cut_cells, fluid_cells,
                 free_node_blocks, free_mask_blocks, exhausted, pool_growths, static_rebuilt, nodes_per_level,
                 ms] = f;
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
            .stages = stages,
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

inline std::vector<gust::Vec3> to_cpp(const gust_vec3* points, std::size_t count) {
    std::vector<gust::Vec3> out(count);
    for (std::size_t i = 0; i < count; ++i)
        out[i] = to_cpp(points[i]);
    return out;
}

inline void to_c(const std::vector<gust::Vec3>& in, gust_vec3* out) {
    for (std::size_t i = 0; i < in.size(); ++i)
        out[i] = to_c(in[i]);
}

inline const gust::DeviceRequirements& static_requirements() {
    static const gust::DeviceRequirements requirements = gust::device_requirements();
    return requirements;
}

inline std::uint32_t count32(std::size_t n) {
    return static_cast<std::uint32_t>(n);
}

/// A debug call that fills a list of C++ entries, run for a C array of `capacity` entries: the call
/// writes into a list of its own type and `convert` turns each of the first min(capacity, total) into a
/// C entry, which keeps the C and C++ structs free to differ at the cost of a copy (these are debug
/// calls). `*count` receives the total, as the C++ call's count does.
template <class Entry, class CEntry, class Call, class Convert>
inline gust::Outcome fill_list(CEntry* out, std::size_t capacity, std::size_t* count, const char* name,
                               Call call, Convert convert) {
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

} // namespace gust::capi
