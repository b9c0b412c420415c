// The C ABI (gust.h) over gust::System. Systems are handed out as serial numbers looked up in a registry,
// so a NULL, destroyed or made-up handle fails with GUST_ERROR_INVALID_HANDLE instead of being dereferenced,
// and a destroyed handle never aliases a later system. Messages live in the system (or, without one, in
// thread-local storage), and no C++ exception crosses into C.
#include "gust_c_internal.hpp"

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
static_assert(GUST_ERROR_BUSY == static_cast<int>(gust::ErrorCode::Busy));
static_assert(GUST_ERROR_NOT_ENABLED == static_cast<int>(gust::ErrorCode::NotEnabled));

static_assert(GUST_WIND_READING_WIND == static_cast<int>(gust::WindReading::Wind));
static_assert(GUST_WIND_READING_SOLVER == static_cast<int>(gust::WindReading::Solver));

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
static_assert(sizeof(gust_vec3) == sizeof(gust::Vec3) && alignof(gust_vec3) == alignof(gust::Vec3));
static_assert(sizeof(gust_wind_texture::world_to_texture) == sizeof(gust::Mat4::m));
static_assert(sizeof(gust_wind_texture::extent) == sizeof(gust::WindTexture::extent));
static_assert(sizeof(gust_voxel_grid_info::resolution) == sizeof(gust::VoxelGridInfo::resolution));

using namespace gust::capi;

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
        gust::MeshSkin skin;
        gust::Outcome outcome = s.create_mesh(to_cpp(*desc, skin), id);
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

// The palette's floats are read as gust::Mat4s, which are 16 floats and nothing else.
static_assert(sizeof(gust::Mat4) == 16 * sizeof(float) && alignof(gust::Mat4) == alignof(float));

gust_result gust_system_set_bones(gust_system system, gust_mesh mesh, const float* palette, uint32_t count,
                                  bool teleport) {
    return on_system(system, "gust_system_set_bones", [&](gust::System& s) {
        return s.set_bones(mesh, reinterpret_cast<const gust::Mat4*>(palette), count, teleport);
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

gust_result gust_system_shift_origin(gust_system system, gust_vec3 offset) {
    return on_system(system, "gust_system_shift_origin",
                     [&](gust::System& s) { return s.shift_origin(to_cpp(offset)); });
}

gust_result gust_system_step(gust_system system, float dt) {
    return on_system(system, "gust_system_step", [&](gust::System& s) { return s.step(dt); });
}

gust_result gust_system_step_commands(gust_system system, float dt, VkCommandBuffer commands) {
    return on_system(system, "gust_system_step_commands",
                     [&](gust::System& s) { return s.step(dt, commands); });
}

} // extern "C"
