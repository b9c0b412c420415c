/* The C ABI (gust.h) driven from C: a small world on the validated own device (lavapipe in CI) with a
 * static and a moving box, queries, the wind texture and stats; a host engine's device with host commands and
 * a vertex buffer; and every error path the header promises (each failing call returns its code and a
 * message that names the function). No test framework: CHECK prints file:line and the expression, and main
 * returns 1 if any failed. */
#include <dlfcn.h>
#include <gust/gust.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int g_failures = 0;

static void check_failed(const char* file, int line, const char* expression) {
    fprintf(stderr, "%s:%d: CHECK failed: %s\n", file, line, expression);
    ++g_failures;
}

/// Records a failure of `cond` and goes on.
#define CHECK(cond) ((cond) ? (void)0 : check_failed(__FILE__, __LINE__, #cond))

static const char* result_name(gust_result r) {
    switch (r) {
    case GUST_OK:
        return "GUST_OK";
    case GUST_ERROR_INVALID_ARGUMENT:
        return "GUST_ERROR_INVALID_ARGUMENT";
    case GUST_ERROR_INVALID_HANDLE:
        return "GUST_ERROR_INVALID_HANDLE";
    case GUST_ERROR_VERSION_MISMATCH:
        return "GUST_ERROR_VERSION_MISMATCH";
    case GUST_ERROR_DEVICE_UNSUPPORTED:
        return "GUST_ERROR_DEVICE_UNSUPPORTED";
    case GUST_ERROR_DEVICE_FAILURE:
        return "GUST_ERROR_DEVICE_FAILURE";
    case GUST_ERROR_NOT_READY:
        return "GUST_ERROR_NOT_READY";
    case GUST_ERROR_IO:
        return "GUST_ERROR_IO";
    case GUST_ERROR_UNSUPPORTED:
        return "GUST_ERROR_UNSUPPORTED";
    case GUST_ERROR_BUSY:
        return "GUST_ERROR_BUSY";
    case GUST_ERROR_NOT_ENABLED:
        return "GUST_ERROR_NOT_ENABLED";
    }
    return "(not a gust_result)";
}

/* `call` is the source text of the call: its message must start with the function's name and a colon, which
 * also shows it is this call's message and not an older one. */
static void check_result(const char* file, int line, const char* call, gust_result got, gust_result want,
                         const char* message) {
    if (got != want) {
        fprintf(stderr, "%s:%d: %s returned %s, expected %s (message: %s)\n", file, line, call,
                result_name(got), result_name(want), message ? message : "(null)");
        ++g_failures;
        return;
    }
    if (want == GUST_OK) return;
    const size_t name_length = strcspn(call, "(");
    if (!message || strncmp(message, call, name_length) != 0 || message[name_length] != ':' ||
        strlen(message) <= name_length + 2) {
        fprintf(stderr, "%s:%d: %s: message \"%s\" does not name the function and the reason\n", file, line,
                call, message ? message : "(null)");
        ++g_failures;
    }
}

/// `call` on a system returns `want`; a failure's message comes from gust_system_last_error(system).
#define CHECK_RESULT(system, call, want)                                                                     \
    do {                                                                                                     \
        const gust_result result_ = (call);                                                                  \
        check_result(__FILE__, __LINE__, #call, result_, (want), gust_system_last_error(system));            \
    } while (0)

/// `call` without a live system returns `want`; a failure's message comes from gust_last_create_error().
#define CHECK_FREE_RESULT(call, want)                                                                        \
    do {                                                                                                     \
        const gust_result result_ = (call);                                                                  \
        check_result(__FILE__, __LINE__, #call, result_, (want), gust_last_create_error());                  \
    } while (0)

static float absf(float x) {
    return x < 0.0f ? -x : x;
}

static gust_vec3 vec3(float x, float y, float z) {
    gust_vec3 v = {x, y, z};
    return v;
}

/// uvw = m * (p, 1) for a column-major m.
static gust_vec3 transform_point(const float m[16], gust_vec3 p) {
    return vec3(m[0] * p.x + m[4] * p.y + m[8] * p.z + m[12], m[1] * p.x + m[5] * p.y + m[9] * p.z + m[13],
                m[2] * p.x + m[6] * p.y + m[10] * p.z + m[14]);
}

/// Uniform scale `s` then translation `t`, column-major.
static void scale_translate(float m[16], float s, gust_vec3 t) {
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = s;
    m[15] = 1.0f;
    m[12] = t.x;
    m[13] = t.y;
    m[14] = t.z;
}

/* The cube [-1, 1]^3: eight corners, padded to a 16-byte stride to exercise strided positions, and twelve
 * triangles. */
static const float kBoxPositions[8 * 4] = {-1, -1, -1, 0, 1, -1, -1, 0, 1, 1, -1, 0, -1, 1, -1, 0,
                                           -1, -1, 1,  0, 1, -1, 1,  0, 1, 1, 1,  0, -1, 1, 1,  0};
static const uint32_t kBoxIndices[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                         3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};

static gust_mesh_desc box_desc(void) {
    gust_mesh_desc desc;
    CHECK(gust_mesh_desc_defaults(&desc) == GUST_OK);
    desc.positions = kBoxPositions;
    desc.vertex_count = 8;
    desc.stride = 4 * sizeof(float);
    desc.indices = kBoxIndices;
    desc.index_count = 36;
    return desc;
}

/* Host hooks that count what gust does with them. */
typedef struct hook_counts {
    long allocations, frees, bad_alignments;
    atomic_int errors, asserts;
} hook_counts;

static void* counting_allocate(void* user, size_t bytes, size_t alignment) {
    hook_counts* counts = (hook_counts*)user;
    if (alignment == 0 || (alignment & (alignment - 1)) != 0) {
        ++counts->bad_alignments;
        return NULL;
    }
    if (alignment < sizeof(void*)) alignment = sizeof(void*);
    /* aligned_alloc wants a size that is a multiple of the alignment. */
    const size_t size = bytes == 0 ? alignment : (bytes + alignment - 1) / alignment * alignment;
    void* memory = aligned_alloc(alignment, size);
    if (memory) ++counts->allocations;
    return memory;
}

static void counting_free(void* user, void* memory) {
    hook_counts* counts = (hook_counts*)user;
    if (memory) ++counts->frees;
    free(memory);
}

static void counting_log(void* user, gust_log_level level, const char* message) {
    hook_counts* counts = (hook_counts*)user;
    if (level == GUST_LOG_ERROR) atomic_fetch_add(&counts->errors, 1);
    if (level != GUST_LOG_INFO)
        fprintf(stderr, "[gust %s] %s\n", level == GUST_LOG_ERROR ? "error" : "warning", message);
}

static void counting_assert_failed(void* user, const char* expression, const char* file, int line) {
    hook_counts* counts = (hook_counts*)user;
    atomic_fetch_add(&counts->asserts, 1);
    fprintf(stderr, "[gust assert] %s:%d: %s\n", file, line, expression);
}

/* The world every GPU test uses: 16x8x16 cells of 1 m around (0, 4, 0), four voxels per cell. */
static const gust_vec3 kFocus = {0.0f, 4.0f, 0.0f};
static const gust_vec3 kAmbient = {4.0f, 0.0f, 0.0f};

static gust_system_desc small_world_desc(hook_counts* counts) {
    gust_system_desc desc;
    CHECK(gust_system_desc_defaults(&desc) == GUST_OK);
    desc.validation = true;
    desc.domain.cells[0] = 16;
    desc.domain.cells[1] = 8;
    desc.domain.cells[2] = 16;
    desc.domain.cell_size = 1.0f;
    desc.domain.voxels_per_cell = 4;
    desc.domain.branching = 4;
    desc.domain.focus = kFocus;
    if (counts) {
        desc.hooks.user = counts;
        desc.hooks.allocate = counting_allocate;
        desc.hooks.free = counting_free;
        desc.hooks.log = counting_log;
        desc.hooks.assert_failed = counting_assert_failed;
    }
    return desc;
}

static void reports_its_version_and_device_requirements(void) {
    CHECK(gust_library_version() == GUST_HEADER_VERSION);
    CHECK(GUST_HEADER_VERSION ==
          VK_MAKE_API_VERSION(0, GUST_VERSION_MAJOR, GUST_VERSION_MINOR, GUST_VERSION_PATCH));

    gust_device_requirements requirements;
    CHECK_FREE_RESULT(gust_get_device_requirements(&requirements), GUST_OK);
    /* Vulkan 1.2: Godot 4 hosts gust on a 1.2 device (docs/godot.md). */
    CHECK(requirements.api_version == VK_API_VERSION_1_2);
    CHECK(requirements.feature_count > 0);
    for (uint32_t i = 0; i < requirements.feature_count; ++i)
        CHECK(requirements.features[i] && requirements.features[i][0] != '\0');
    for (uint32_t i = 0; i < requirements.extension_count; ++i)
        CHECK(requirements.extensions[i] && requirements.extensions[i][0] != '\0');
    for (uint32_t i = 0; i < requirements.optional_extension_count; ++i)
        CHECK(requirements.optional_extensions[i] && requirements.optional_extensions[i][0] != '\0');
    CHECK_FREE_RESULT(gust_get_device_requirements(NULL), GUST_ERROR_INVALID_ARGUMENT);

    /* docs/design.md: shaders take buffers by device address, so bufferDeviceAddress is among the features.
     */
    VkPhysicalDeviceVulkan13Features features13 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features features12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    features12.pNext = &features13;
    VkPhysicalDeviceFeatures2 features = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    features.pNext = &features12;
    CHECK_FREE_RESULT(gust_add_required_features(&features), GUST_OK);
    CHECK(features12.bufferDeviceAddress == VK_TRUE);

    VkPhysicalDeviceFeatures2 bare = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    CHECK_FREE_RESULT(gust_add_required_features(&bare), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_FREE_RESULT(gust_add_required_features(NULL), GUST_ERROR_INVALID_ARGUMENT);
}

static void fills_the_documented_defaults(void) {
    gust_system_desc desc;
    memset(&desc, 0xff, sizeof desc);
    CHECK_FREE_RESULT(gust_system_desc_defaults(&desc), GUST_OK);
    CHECK(desc.header_version == GUST_HEADER_VERSION);
    CHECK(desc.host == NULL && desc.device == NULL && !desc.validation);
    CHECK(desc.submission == GUST_SUBMISSION_OWN_QUEUE && desc.frames_in_flight == 2 &&
          desc.voxelize == GUST_VOXELIZE_AUTO);
    CHECK(desc.domain.cells[0] == 32 && desc.domain.cells[1] == 16 && desc.domain.cells[2] == 32);
    CHECK(desc.domain.cell_size == 1.0f && desc.domain.voxels_per_cell == 4 && desc.domain.branching == 4);
    CHECK(desc.domain.focus.x == 0.0f && desc.domain.focus.y == 0.0f && desc.domain.focus.z == 0.0f);
    CHECK(desc.domain.hysteresis == 8 && desc.domain.cascades == 1 && desc.domain.ratio == 4);
    CHECK(desc.wind.tolerance == 1e-5f && desc.wind.max_cycles == 32);
    CHECK(desc.wind.pressure == GUST_PRESSURE_MULTIGRID_PCG && desc.wind.max_iterations == 4000);
    CHECK(desc.pipeline_cache == NULL && !desc.snapshot);
    CHECK(desc.wind.vorticity == 0.2f && desc.wind.viscosity == 0.0f);
    CHECK(desc.wind.advection == GUST_ADVECTION_MACCORMACK && desc.wind.max_solid_speed == 50.0f &&
          desc.wind.cycles_per_step == 2);
    CHECK(desc.hooks.user == NULL && desc.hooks.allocate == NULL && desc.hooks.free == NULL &&
          desc.hooks.log == NULL && desc.hooks.assert_failed == NULL);
    /* The inline gust_system_desc_defaults calls gust_system_desc_init, whose name the message carries. */
    CHECK(gust_system_desc_defaults(NULL) == GUST_ERROR_INVALID_ARGUMENT);
    CHECK_FREE_RESULT(gust_system_desc_init(NULL, GUST_HEADER_VERSION), GUST_ERROR_INVALID_ARGUMENT);

    const uint32_t next_minor = GUST_HEADER_VERSION + (1u << 12);
    CHECK_FREE_RESULT(gust_system_desc_init(&desc, next_minor), GUST_ERROR_VERSION_MISMATCH);
    CHECK(desc.header_version == next_minor);

    gust_mesh_desc mesh;
    memset(&mesh, 0xff, sizeof mesh);
    CHECK_FREE_RESULT(gust_mesh_desc_defaults(&mesh), GUST_OK);
    CHECK(mesh.positions == NULL && mesh.vertex_count == 0 && mesh.stride == 12);
    CHECK(mesh.indices == NULL && mesh.index_count == 0 && !mesh.deforming);
    CHECK_FREE_RESULT(gust_mesh_desc_defaults(NULL), GUST_ERROR_INVALID_ARGUMENT);

    gust_wind_emitter emitter;
    memset(&emitter, 0xff, sizeof emitter);
    CHECK_FREE_RESULT(gust_wind_emitter_defaults(&emitter), GUST_OK);
    CHECK(emitter.type == GUST_WIND_EMITTER_OMNI);
    CHECK(emitter.position.x == 0.0f && emitter.position.y == 0.0f && emitter.position.z == 0.0f);
    CHECK(emitter.direction.x == 1.0f && emitter.direction.y == 0.0f && emitter.direction.z == 0.0f);
    CHECK(emitter.radius == 1.0f && emitter.strength == 0.0f && emitter.falloff == 1.0f &&
          emitter.length == 0.0f);
    CHECK_FREE_RESULT(gust_wind_emitter_defaults(NULL), GUST_ERROR_INVALID_ARGUMENT);
}

static void rejects_bad_creation_without_touching_the_device(void) {
    gust_system system = (gust_system)1;
    CHECK_FREE_RESULT(gust_system_create(NULL, &system), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(system == NULL);

    gust_system_desc desc = small_world_desc(NULL);
    CHECK_FREE_RESULT(gust_system_create(&desc, NULL), GUST_ERROR_INVALID_ARGUMENT);

    desc.header_version = GUST_HEADER_VERSION + (1u << 12);
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_VERSION_MISMATCH);
    CHECK(system == NULL);
    desc.header_version = GUST_HEADER_VERSION + (1u << 22);
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_VERSION_MISMATCH);

    desc = small_world_desc(NULL);
    desc.hooks.allocate = counting_allocate;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);

    desc = small_world_desc(NULL);
    desc.domain.cell_size = NAN;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    /* Cells whose voxels are below 1e-4 m, or cells above 1000 m (a cell of 1e-30 m made every solve
       diverge). */
    desc.domain.cell_size = 1e-30f;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc.domain.cell_size = 3e-4f;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc.domain.cell_size = 1e30f;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc = small_world_desc(NULL);
    desc.domain.branching = 3;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc = small_world_desc(NULL);
    desc.voxelize = (gust_voxelize_path)3;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc = small_world_desc(NULL);
    desc.wind.advection = (gust_advection)3;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc = small_world_desc(NULL);
    desc.wind.pressure = (gust_pressure)3;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc = small_world_desc(NULL);
    desc.wind.pressure = GUST_PRESSURE_JACOBI;
    desc.wind.max_iterations = 0;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    desc = small_world_desc(NULL);
    desc.submission = GUST_SUBMISSION_HOST_COMMANDS; /* needs a host device */
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    gust_host_device host;
    memset(&host, 0, sizeof host);
    host.enabled_extension_count = 1;
    desc = small_world_desc(NULL);
    desc.host = &host;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(system == NULL);
}

static void rejects_bad_meshes_and_instances(gust_system system, gust_mesh box, gust_instance placed) {
    gust_mesh mesh = 7;
    gust_mesh_desc desc = box_desc();
    uint32_t bad_indices[36];
    memcpy(bad_indices, kBoxIndices, sizeof bad_indices);
    bad_indices[17] = 8; /* == vertex_count */
    desc.indices = bad_indices;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &mesh), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(mesh == 0);

    desc = box_desc();
    desc.stride = 8;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &mesh), GUST_ERROR_INVALID_ARGUMENT);
    desc = box_desc();
    desc.index_count = 35;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &mesh), GUST_ERROR_INVALID_ARGUMENT);
    desc = box_desc();
    desc.positions = NULL;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &mesh), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_create_mesh(system, NULL, &mesh), GUST_ERROR_INVALID_ARGUMENT);
    desc = box_desc();
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, NULL), GUST_ERROR_INVALID_ARGUMENT);

    float transform[16];
    scale_translate(transform, 1.0f, vec3(0.0f, 2.0f, 0.0f));
    gust_instance instance = 7;
    CHECK_RESULT(system, gust_system_create_instance(system, 0, transform, false, &instance),
                 GUST_ERROR_INVALID_HANDLE);
    CHECK(instance == 0);
    CHECK_RESULT(system, gust_system_create_instance(system, box, NULL, false, &instance),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_create_instance(system, box, transform, false, NULL),
                 GUST_ERROR_INVALID_ARGUMENT);
    transform[13] = NAN;
    CHECK_RESULT(system, gust_system_create_instance(system, box, transform, false, &instance),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_transform(system, placed, transform, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    transform[13] = INFINITY;
    CHECK_RESULT(system, gust_system_set_transform(system, placed, transform, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_transform(system, placed, NULL, false), GUST_ERROR_INVALID_ARGUMENT);
    scale_translate(transform, 1.0f, vec3(0.0f, 2.0f, 0.0f));
    float previous[16];
    scale_translate(previous, 1.0f, vec3(0.0f, 2.0f, NAN));
    CHECK_RESULT(system, gust_system_create_moving_instance(system, box, transform, previous, &instance),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK(instance == 0);
    CHECK_RESULT(system, gust_system_create_moving_instance(system, box, transform, NULL, &instance),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_create_moving_instance(system, box, NULL, transform, &instance),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_create_moving_instance(system, box, transform, transform, NULL),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_create_moving_instance(system, 0, transform, transform, &instance),
                 GUST_ERROR_INVALID_HANDLE);

    /* A mesh in use cannot go; once its instance is gone it can, and both ids are dead for good. */
    CHECK_RESULT(system, gust_system_destroy_mesh(system, box), GUST_ERROR_INVALID_HANDLE);
    scale_translate(transform, 1.0f, vec3(0.0f, 2.0f, 0.0f));
    gust_mesh spare = 0;
    desc = box_desc();
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &spare), GUST_OK);
    CHECK_RESULT(system, gust_system_create_instance(system, spare, transform, false, &instance), GUST_OK);
    CHECK(instance != 0 && instance != placed);
    CHECK_RESULT(system, gust_system_destroy_instance(system, instance), GUST_OK);
    CHECK_RESULT(system, gust_system_set_transform(system, instance, transform, false),
                 GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_destroy_instance(system, instance), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_destroy_instance(system, 0), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_destroy_mesh(system, spare), GUST_OK);
    CHECK_RESULT(system, gust_system_destroy_mesh(system, spare), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_create_instance(system, spare, transform, false, &instance),
                 GUST_ERROR_INVALID_HANDLE);

    /* Vertices: only deforming meshes take them, and only as many as they have; a vertex buffer needs a host
     * device. */
    CHECK_RESULT(system, gust_system_set_vertices(system, box, kBoxPositions, 8, 16, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    gust_mesh skinned = 0;
    desc = box_desc();
    desc.deforming = true;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &skinned), GUST_OK);
    CHECK_RESULT(system, gust_system_set_vertices(system, skinned, kBoxPositions, 8, 16, false), GUST_OK);
    CHECK_RESULT(system, gust_system_set_vertices(system, skinned, kBoxPositions, 7, 16, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_vertices(system, skinned, NULL, 8, 16, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_vertices(system, 12345, kBoxPositions, 8, 16, false),
                 GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_set_vertices_buffer(system, skinned, VK_NULL_HANDLE, 0, 8, false),
                 GUST_ERROR_INVALID_ARGUMENT);

    /* Bones: a skin of two joints, the box's top (y = 1) following joint 1; only a deforming mesh with a skin
     * takes a palette, of exactly its joint count, finite. */
    CHECK_RESULT(system, gust_system_set_bones(system, skinned, transform, 1, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    uint16_t joints[8 * 4] = {0};
    float weights[8 * 4] = {0.0f};
    for (int v = 0; v < 8; ++v) {
        joints[4 * v] = kBoxPositions[4 * v + 1] > 0.0f ? 1 : 0;
        weights[4 * v] = 1.0f;
    }
    gust_mesh_skin skin = {2, joints, weights};
    gust_mesh boned = 0;
    desc = box_desc();
    desc.skin = &skin;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &boned), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(boned == 0);
    desc.deforming = true;
    weights[5] = NAN;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &boned), GUST_ERROR_INVALID_ARGUMENT);
    weights[5] = 0.0f;
    joints[6] = 2;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &boned), GUST_ERROR_INVALID_ARGUMENT);
    joints[6] = 0;
    CHECK_RESULT(system, gust_system_create_mesh(system, &desc, &boned), GUST_OK);
    float palette[2 * 16];
    scale_translate(palette, 1.0f, vec3(0.0f, 0.0f, 0.0f));
    scale_translate(palette + 16, 1.0f, vec3(0.0f, 0.5f, 0.0f));
    CHECK_RESULT(system, gust_system_set_bones(system, boned, palette, 2, false), GUST_OK);
    CHECK_RESULT(system, gust_system_set_bones(system, boned, palette, 2, true), GUST_OK);
    CHECK_RESULT(system, gust_system_set_bones(system, boned, palette, 1, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_bones(system, boned, NULL, 2, false), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_bones(system, box, palette, 2, false), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_bones(system, 12345, palette, 2, false), GUST_ERROR_INVALID_HANDLE);
    palette[16 + 13] = NAN;
    CHECK_RESULT(system, gust_system_set_bones(system, boned, palette, 2, false),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_destroy_mesh(system, boned), GUST_OK);
    CHECK_RESULT(system, gust_system_destroy_mesh(system, skinned), GUST_OK);
}

static void rejects_bad_frame_inputs(gust_system system) {
    CHECK_RESULT(system, gust_system_step(system, 0.0f), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_step(system, -0.02f), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_step(system, NAN), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_step(system, INFINITY), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_step(system, 1e6f), GUST_ERROR_INVALID_ARGUMENT);

    CHECK_RESULT(system, gust_system_set_ambient(system, vec3(NAN, 0.0f, 0.0f)), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_focus(system, vec3(0.0f, INFINITY, 0.0f)),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_shift_origin(system, vec3(NAN, 0.0f, 0.0f)),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_shift_origin(system, vec3(1e30f, 0.0f, 0.0f)),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_shift_origin(system, vec3(0.0f, 0.0f, 0.0f)), GUST_OK);

    gust_wind_emitter emitters[GUST_MAX_EMITTERS + 1];
    for (int i = 0; i < GUST_MAX_EMITTERS + 1; ++i)
        CHECK(gust_wind_emitter_defaults(&emitters[i]) == GUST_OK);
    CHECK_RESULT(system, gust_system_set_emitters(system, emitters, GUST_MAX_EMITTERS + 1),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_emitters(system, NULL, 1), GUST_ERROR_INVALID_ARGUMENT);
    emitters[0].radius = 0.0f;
    CHECK_RESULT(system, gust_system_set_emitters(system, emitters, 1), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(gust_wind_emitter_defaults(&emitters[0]) == GUST_OK);
    emitters[0].type = (gust_wind_emitter_type)99;
    CHECK_RESULT(system, gust_system_set_emitters(system, emitters, 1), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_set_emitters(system, NULL, 0), GUST_OK);

    /* Own queue: there is nothing to record into a host's command buffer. */
    CHECK_RESULT(system, gust_system_step_commands(system, 0.05f, VK_NULL_HANDLE),
                 GUST_ERROR_INVALID_ARGUMENT);
}

static void rejects_bad_queries(gust_system system) {
    gust_vec3 points[2] = {{0.0f, 4.0f, 0.0f}, {NAN, 0.0f, 0.0f}};
    gust_vec3 velocities[2];
    gust_query query = 7;
    CHECK_RESULT(system, gust_system_query(system, points, 2, velocities), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_query(system, NULL, 2, velocities), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_query(system, points, 1, NULL), GUST_ERROR_INVALID_ARGUMENT);
    /* A count past the limit is refused before anything is read (it was an out-of-memory DeviceFailure). */
    CHECK_RESULT(system, gust_system_query(system, points, (size_t)GUST_MAX_QUERY_POINTS + 1, velocities),
                 GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_query_async(system, points, 2, &query), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(query == 0);
    CHECK_RESULT(system, gust_system_query_async(system, points, 1, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_fetch(system, 987654321, velocities, 1), GUST_ERROR_INVALID_HANDLE);

    gust_wind_sample sample;
    CHECK_RESULT(system, gust_system_wind_at(system, points[1], &sample), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_wind_at(system, points[0], NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_wind_texture(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    gust_wind_texture cascade;
    CHECK_RESULT(system, gust_system_cascade_texture(system, 0, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_cascade_texture(system, 1, &cascade), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_stats(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_stats_pass_count(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_domain_origin(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_device_name(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_queue_info(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_export_vdb(system, NULL), GUST_ERROR_INVALID_ARGUMENT);

    gust_voxel_coord voxels[2];
    gust_tree_node nodes[2];
    size_t count = 7;
    CHECK_RESULT(system, gust_system_debug_voxel_grid(system, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_debug_voxels(system, voxels, 2, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_debug_voxels(system, NULL, 2, &count), GUST_ERROR_INVALID_ARGUMENT);
    CHECK(count == 0);
    CHECK_RESULT(system, gust_system_debug_tree_nodes(system, nodes, 2, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_debug_tree_nodes(system, NULL, 2, &count), GUST_ERROR_INVALID_ARGUMENT);
}

/* Dispatch timing: the next step's passes are its dispatches, one each, named after their pipelines;
 * off again, the step after gives the `passes` passes it gave before. */
static void times_each_dispatch(gust_system system, uint32_t passes) {
    CHECK_RESULT(system, gust_system_set_dispatch_timing(system, true), GUST_OK);
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    gust_frame_stats stats;
    CHECK_RESULT(system, gust_system_stats(system, &stats), GUST_OK);
    uint32_t timed = 0;
    CHECK_RESULT(system, gust_system_stats_pass_count(system, &timed), GUST_OK);
    CHECK(timed == stats.dispatches && timed > passes);
    int advected = 0;
    for (uint32_t i = 0; i < timed; ++i) {
        const char* name = NULL;
        double ms = -1.0;
        CHECK_RESULT(system, gust_system_stats_pass(system, i, &name, &ms), GUST_OK);
        CHECK(name && strncmp(name, "gust ", 5) == 0);
        CHECK(isfinite(ms) && ms >= 0.0);
        advected += name && strstr(name, "advect") != NULL;
    }
    CHECK(advected >= 1);
    CHECK_RESULT(system, gust_system_set_dispatch_timing(system, false), GUST_OK);
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    CHECK_RESULT(system, gust_system_stats_pass_count(system, &timed), GUST_OK);
    CHECK(timed == passes);
}

static int equal3(gust_vec3 a, gust_vec3 b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
}
static int near3(gust_vec3 a, gust_vec3 b, float tolerance) {
    return absf(a.x - b.x) <= tolerance && absf(a.y - b.y) <= tolerance && absf(a.z - b.z) <= tolerance;
}
static int finite3(gust_vec3 v) {
    return isfinite(v.x) && isfinite(v.y) && isfinite(v.z);
}

/* The debug views of a world whose static box spans [-1.5, 1.5] x [0.5, 3.5] x [-1.5, 1.5] m and whose moving
 * box is the 1 m cube around `mover_at`, after a step whose statistics are `stats`. The grid is
 * small_world_desc's: 64 voxels of 0.25 m (the longest axis needs 16 * 4, a power of the branching 4) from
 * the domain's corner. */
static void shows_voxels_and_tree_nodes(gust_system system, const gust_frame_stats* stats,
                                        gust_vec3 mover_at) {
    gust_voxel_grid_info grid;
    CHECK_RESULT(system, gust_system_debug_voxel_grid(system, &grid), GUST_OK);
    CHECK(equal3(grid.origin, vec3(-8.0f, 0.0f, -8.0f)));
    CHECK(grid.voxel_size == 0.25f);
    CHECK(grid.resolution[0] == 64 && grid.resolution[1] == 64 && grid.resolution[2] == 64);
    CHECK(grid.depth == 3 && grid.branching == 4);

    size_t count = 0;
    CHECK_RESULT(system, gust_system_debug_voxels(system, NULL, 0, &count), GUST_OK);
    CHECK(count == stats->voxels);
    gust_voxel_coord* voxels = (gust_voxel_coord*)malloc((count + 1) * sizeof *voxels);
    CHECK(voxels != NULL);
    if (!voxels) return;
    size_t again = 0;
    CHECK_RESULT(system, gust_system_debug_voxels(system, voxels, count + 1, &again), GUST_OK);
    CHECK(again == count);
    /* Every voxel meets one of the boxes: it lies within a box grown by one voxel. */
    const float lo[2][3] = {{-1.5f, 0.5f, -1.5f}, {mover_at.x - 0.5f, mover_at.y - 0.5f, mover_at.z - 0.5f}};
    const float hi[2][3] = {{1.5f, 3.5f, 1.5f}, {mover_at.x + 0.5f, mover_at.y + 0.5f, mover_at.z + 0.5f}};
    size_t off_boxes = 0;
    for (size_t v = 0; v < count; ++v) {
        const uint32_t c[3] = {voxels[v].i, voxels[v].j, voxels[v].k};
        const float origin[3] = {grid.origin.x, grid.origin.y, grid.origin.z};
        int on_a_box = 0;
        for (int b = 0; b < 2; ++b) {
            int within = 1;
            for (int a = 0; a < 3; ++a) {
                const float min = origin[a] + (float)c[a] * grid.voxel_size;
                within = within && min >= lo[b][a] - grid.voxel_size - 1e-4f &&
                         min + grid.voxel_size <= hi[b][a] + grid.voxel_size + 1e-4f;
            }
            on_a_box = on_a_box || within;
        }
        off_boxes += !on_a_box;
    }
    CHECK(off_boxes == 0);
    /* A short array gets the first voxels and the total. */
    gust_voxel_coord first[3];
    CHECK_RESULT(system, gust_system_debug_voxels(system, first, 3, &again), GUST_OK);
    CHECK(again == count);
    CHECK(count >= 3 && memcmp(first, voxels, sizeof first) == 0);
    free(voxels);

    CHECK_RESULT(system, gust_system_debug_tree_nodes(system, NULL, 0, &count), GUST_OK);
    CHECK(count == stats->nodes);
    gust_tree_node* nodes = (gust_tree_node*)malloc(count * sizeof *nodes);
    CHECK(nodes != NULL);
    if (!nodes) return;
    CHECK_RESULT(system, gust_system_debug_tree_nodes(system, nodes, count, &again), GUST_OK);
    CHECK(again == count);
    CHECK(count > 1 && nodes[0].level == 0 && nodes[0].refined);
    CHECK(equal3(nodes[0].min, grid.origin) && nodes[0].size == 16.0f);
    CHECK(nodes[0].state == GUST_TREE_NODE_STATIC);
    int reached = 0, levels_in_order = 1;
    for (size_t n = 1; n < count; ++n) {
        levels_in_order =
            levels_in_order && nodes[n].level >= nodes[n - 1].level && nodes[n].level < grid.depth;
        reached = reached || nodes[n].state == GUST_TREE_NODE_REACHED;
    }
    CHECK(levels_in_order);
    CHECK(reached); /* the moving box */
    free(nodes);
}

/* Points inside and outside the 16x8x16 m domain around kFocus; those outside get the ambient wind exactly.
 */
enum { kInside = 2, kPoints = 5 };
static const gust_vec3 kProbes[kPoints] = {
    {-6.0f, 6.0f, -6.0f}, /* upwind, away from both boxes */
    {0.0f, 5.5f, 0.0f},   /* above the static box */
    {100.0f, 4.0f, 0.0f}, /* outside: downwind */
    {0.0f, -5.0f, 0.0f},  /* outside: below */
    {0.0f, 50.0f, 3.0f},  /* outside: above */
};

static void simulates_a_small_world(void) {
    hook_counts counts = {0};
    gust_system_desc desc = small_world_desc(&counts);
    gust_system system = NULL;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_OK);
    if (!system) return;
    CHECK(strcmp(gust_system_last_error(system), "") == 0);

    gust_mesh box = 0;
    gust_mesh_desc mesh = box_desc();
    CHECK_RESULT(system, gust_system_create_mesh(system, &mesh, &box), GUST_OK);
    CHECK(box != 0);
    /* The static box spans [-1.5, 1.5] x [0.5, 3.5] x [-1.5, 1.5] m; the moving one is a 1 m cube. */
    float transform[16];
    scale_translate(transform, 1.5f, vec3(0.0f, 2.0f, 0.0f));
    gust_instance wall = 0, mover = 0;
    CHECK_RESULT(system, gust_system_create_instance(system, box, transform, false, &wall), GUST_OK);
    gust_vec3 mover_at = vec3(-5.0f, 2.0f, 4.0f);
    scale_translate(transform, 0.5f, mover_at);
    CHECK_RESULT(system, gust_system_create_instance(system, box, transform, true, &mover), GUST_OK);
    CHECK(wall != 0 && mover != 0 && wall != mover);
    CHECK_RESULT(system, gust_system_set_ambient(system, kAmbient), GUST_OK);
    CHECK_RESULT(system, gust_system_set_focus(system, kFocus), GUST_OK);
    gust_wind_emitter fan;
    CHECK(gust_wind_emitter_defaults(&fan) == GUST_OK);
    fan.type = GUST_WIND_EMITTER_DIRECTIONAL;
    fan.position = vec3(4.0f, 2.0f, -4.0f);
    fan.direction = vec3(0.0f, 0.0f, 1.0f);
    fan.radius = 2.0f;
    fan.strength = 3.0f;
    CHECK_RESULT(system, gust_system_set_emitters(system, &fan, 1), GUST_OK);

    /* Asked before the step, answered by it. */
    gust_query query = 0;
    CHECK_RESULT(system, gust_system_query_async(system, kProbes, kPoints, &query), GUST_OK);
    CHECK(query != 0);
    gust_vec3 fetched[kPoints];
    CHECK_RESULT(system, gust_system_fetch(system, query, fetched, kPoints), GUST_ERROR_NOT_READY);

    const int frames = 4;
    for (int frame = 0; frame < frames; ++frame) {
        mover_at.x += 0.25f;
        scale_translate(transform, 0.5f, mover_at);
        CHECK_RESULT(system, gust_system_set_transform(system, mover, transform, false), GUST_OK);
        CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    }

    gust_vec3 velocities[kPoints];
    CHECK_RESULT(system, gust_system_query(system, kProbes, kPoints, velocities), GUST_OK);
    for (int i = 0; i < kPoints; ++i)
        CHECK(finite3(velocities[i]));
    for (int i = kInside; i < kPoints; ++i)
        CHECK(equal3(velocities[i], kAmbient));
    /* Upwind of everything the air moves with the ambient wind (the projection carries the inflow through).
     */
    CHECK(velocities[0].x > 0.0f);
    /* The default reading is the wind (GUST_WIND_READING_WIND); the solver's own field answers the ambient
     * wind outside the domain too; a reading that is none is refused. */
    gust_vec3 read[kPoints];
    CHECK_RESULT(system, gust_system_query_reading(system, kProbes, kPoints, read, GUST_WIND_READING_WIND),
                 GUST_OK);
    for (int i = 0; i < kPoints; ++i)
        CHECK(equal3(read[i], velocities[i]));
    CHECK_RESULT(system, gust_system_query_reading(system, kProbes, kPoints, read, GUST_WIND_READING_SOLVER),
                 GUST_OK);
    for (int i = kInside; i < kPoints; ++i)
        CHECK(equal3(read[i], kAmbient));
    CHECK(read[0].x > 0.0f);
    CHECK_RESULT(system, gust_system_query_reading(system, kProbes, kPoints, read, (gust_wind_reading)7),
                 GUST_ERROR_INVALID_ARGUMENT);

    /* The wrong size is refused without losing the answer; the answer comes once, then the ticket is dead. */
    CHECK_RESULT(system, gust_system_fetch(system, query, fetched, kPoints - 1), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_RESULT(system, gust_system_fetch(system, query, fetched, kPoints), GUST_OK);
    for (int i = 0; i < kPoints; ++i)
        CHECK(finite3(fetched[i]));
    for (int i = kInside; i < kPoints; ++i)
        CHECK(equal3(fetched[i], kAmbient));
    CHECK_RESULT(system, gust_system_fetch(system, query, fetched, kPoints), GUST_ERROR_INVALID_HANDLE);

    /* An asynchronous query asked now is answered by the next step with the same field a blocking query then
     * sees. */
    CHECK_RESULT(system, gust_system_query_async(system, kProbes, kPoints, &query), GUST_OK);
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    CHECK_RESULT(system, gust_system_fetch(system, query, fetched, kPoints), GUST_OK);
    CHECK_RESULT(system, gust_system_query(system, kProbes, kPoints, velocities), GUST_OK);
    for (int i = 0; i < kPoints; ++i)
        CHECK(near3(fetched[i], velocities[i], 1e-6f));

    gust_wind_sample sample;
    CHECK_RESULT(system, gust_system_wind_at(system, kProbes[0], &sample), GUST_OK);
    const float speed2 = velocities[0].x * velocities[0].x + velocities[0].y * velocities[0].y +
                         velocities[0].z * velocities[0].z;
    CHECK(absf(sample.speed * sample.speed - speed2) <= 1e-4f * (1.0f + speed2));
    CHECK(near3(vec3(sample.direction.x * sample.speed, sample.direction.y * sample.speed,
                     sample.direction.z * sample.speed),
                velocities[0], 1e-4f));
    CHECK(isfinite(sample.gust) && sample.gust >= 0.0f);
    /* Far outside, the point and its neighbours all get the ambient wind: 4 m/s along +x, no gust. */
    CHECK_RESULT(system, gust_system_wind_at(system, kProbes[2], &sample), GUST_OK);
    CHECK(sample.speed == 4.0f && equal3(sample.direction, vec3(1.0f, 0.0f, 0.0f)));
    CHECK(sample.gust <= 1e-5f); /* the neighbours' mean is 6 * (4 / 6) m/s, rounded */

    /* docs/design.md: the domain's min corner is centre - cells * cell_size / 2. */
    gust_vec3 origin;
    CHECK_RESULT(system, gust_system_domain_origin(system, &origin), GUST_OK);
    CHECK(equal3(origin, vec3(-8.0f, 0.0f, -8.0f)));

    gust_wind_texture texture;
    CHECK_RESULT(system, gust_system_wind_texture(system, &texture), GUST_OK);
    CHECK(texture.image != VK_NULL_HANDLE && texture.view != VK_NULL_HANDLE &&
          texture.sampler != VK_NULL_HANDLE);
    CHECK(texture.format == VK_FORMAT_R16G16B16A16_SFLOAT);
    CHECK(texture.layout == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
    CHECK(texture.extent[0] == 16 && texture.extent[1] == 8 && texture.extent[2] == 16);
    CHECK(texture.frame == (uint64_t)frames + 1);
    CHECK(near3(transform_point(texture.world_to_texture, origin), vec3(0.0f, 0.0f, 0.0f), 1e-6f));
    CHECK(near3(transform_point(texture.world_to_texture, vec3(8.0f, 8.0f, 8.0f)), vec3(1.0f, 1.0f, 1.0f),
                1e-6f));
    /* One cascade: its texture is the wind texture. */
    gust_wind_texture finest;
    CHECK_RESULT(system, gust_system_cascade_texture(system, 0, &finest), GUST_OK);
    CHECK(finest.image == texture.image && finest.frame == texture.frame);

    gust_frame_stats stats;
    CHECK_RESULT(system, gust_system_stats(system, &stats), GUST_OK);
    CHECK(stats.frame > 0);
    CHECK(stats.fragments > 0 && stats.fragment_bytes > 0);
    /* Both boxes have their faces on voxel boundaries (0.25 m voxels from the corner (-8, 0, -8)), and a
     * voxel is occupied when its closed box meets a triangle, so each face occupies the voxel layers on both
     * sides of it: a cube n voxels wide covers (n + 2)^3 - (n - 2)^3 voxels. Static: 3 m, n = 12; moving: 1
     * m, n = 4. */
    CHECK(stats.voxels == (14 * 14 * 14 - 10 * 10 * 10) + (6 * 6 * 6 - 2 * 2 * 2));
    CHECK(stats.nodes > 0 && stats.pool_bytes > 0 && stats.dense_bytes > 0);
    CHECK(stats.cycles > 0 && isfinite(stats.residual));
    CHECK(stats.divergence_after <= stats.divergence_before);
    CHECK(stats.rejected_triangles == 0);
    CHECK(stats.exhausted == 0 && stats.pool_growths == 0);
    const char* device = NULL;
    CHECK_RESULT(system, gust_system_device_name(system, &device), GUST_OK);
    CHECK(device != NULL && device[0] != '\0');
    uint32_t passes = 0;
    CHECK_RESULT(system, gust_system_stats_pass_count(system, &passes), GUST_OK);
    CHECK(passes > 0);
    for (uint32_t i = 0; i < passes; ++i) {
        const char* name = NULL;
        double ms = -1.0;
        CHECK_RESULT(system, gust_system_stats_pass(system, i, &name, &ms), GUST_OK);
        CHECK(name && name[0] != '\0');
        CHECK(isfinite(ms) && ms >= 0.0);
    }
    CHECK_RESULT(system, gust_system_stats_pass(system, passes, NULL, NULL), GUST_ERROR_INVALID_ARGUMENT);

    shows_voxels_and_tree_nodes(system, &stats, mover_at);

    /* OpenVDB export: a file when built with OpenVDB (a missing directory is an I/O error); without it, a
     * clear refusal. */
    const char* vdb_path = "gust_c_api_test.vdb";
#if GUST_WITH_OPENVDB
    CHECK_RESULT(system, gust_system_export_vdb(system, vdb_path), GUST_OK);
    FILE* file = fopen(vdb_path, "rb");
    CHECK(file != NULL);
    if (file) {
        CHECK(fseek(file, 0, SEEK_END) == 0 && ftell(file) > 0);
        fclose(file);
    }
    remove(vdb_path);
    CHECK_RESULT(system, gust_system_export_vdb(system, "/nonexistent-gust-dir/frame.vdb"), GUST_ERROR_IO);
#else
    CHECK_RESULT(system, gust_system_export_vdb(system, vdb_path), GUST_ERROR_UNSUPPORTED);
    CHECK(strstr(gust_system_last_error(system), "built without OpenVDB") != NULL);
    FILE* file = fopen(vdb_path, "rb");
    CHECK(file == NULL);
    if (file) fclose(file);
#endif

    rejects_bad_meshes_and_instances(system, box, wall);
    rejects_bad_frame_inputs(system);
    rejects_bad_queries(system);
    /* Still stepping after all that. */
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    times_each_dispatch(system, passes);

    CHECK_RESULT(system, gust_system_destroy(system), GUST_OK);
    CHECK(counts.allocations > 0);
    CHECK(counts.allocations == counts.frees);
    CHECK(counts.bad_alignments == 0);
    CHECK(atomic_load(&counts.errors) == 0);
    CHECK(atomic_load(&counts.asserts) == 0);

    /* The destroyed handle is dead, even after another system is created, and so is one never handed out. */
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_destroy(system), GUST_ERROR_INVALID_HANDLE);
    gust_system other = NULL;
    desc = small_world_desc(NULL);
    CHECK_FREE_RESULT(gust_system_create(&desc, &other), GUST_OK);
    CHECK(other != NULL && other != system);
    CHECK_RESULT(system, gust_system_set_ambient(system, kAmbient), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_query(system, kProbes, kPoints, velocities), GUST_ERROR_INVALID_HANDLE);
    size_t count = 0;
    gust_voxel_grid_info grid;
    CHECK_RESULT(system, gust_system_debug_voxel_grid(system, &grid), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(system, gust_system_debug_voxels(system, NULL, 0, &count), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(NULL, gust_system_debug_tree_nodes(NULL, NULL, 0, &count), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(other, gust_system_step(other, 0.05f), GUST_OK);
    CHECK_RESULT(other, gust_system_destroy(other), GUST_OK);
    gust_system made_up = (gust_system)(uintptr_t)0x5eed;
    CHECK_RESULT(made_up, gust_system_step(made_up, 0.05f), GUST_ERROR_INVALID_HANDLE);
    CHECK_RESULT(NULL, gust_system_step(NULL, 0.05f), GUST_ERROR_INVALID_HANDLE);
    CHECK(gust_system_last_error(NULL) == gust_last_create_error());
}

/* A host engine written in C: it loads Vulkan itself, creates a validated instance and a device with gust's
 * requirements, and hands them to gust, which records into the host's command buffer. */
typedef struct host_engine {
    void* loader;
    PFN_vkGetInstanceProcAddr get_instance_proc_addr;
    VkInstance instance;
    VkDebugUtilsMessengerEXT messenger;
    VkPhysicalDevice physical_device;
    uint32_t queue_family;
    VkDevice device;
    VkQueue queue;
    atomic_int validation_messages;
} host_engine;

/// An instance or device function of the host's loader, cast to its type.
#define HOST_LOAD(host, name) ((PFN_##name)(host)->get_instance_proc_addr((host)->instance, #name))

static VKAPI_ATTR VkBool32 VKAPI_CALL host_on_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                      VkDebugUtilsMessageTypeFlagsEXT types,
                                                      const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                      void* user) {
    (void)severity;
    (void)types;
    host_engine* host = (host_engine*)user;
    atomic_fetch_add(&host->validation_messages, 1);
    fprintf(stderr, "[host validation] %s\n", data->pMessage ? data->pMessage : "");
    return VK_FALSE;
}

/* Returns 0 (after a failed CHECK) when the host could not be set up. */
static int host_start(host_engine* host) {
    memset(host, 0, sizeof *host);
    atomic_init(&host->validation_messages, 0);
    host->loader = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_LOCAL);
    CHECK(host->loader != NULL);
    if (!host->loader) return 0;
    /* ISO C has no cast from an object pointer to a function pointer; dlsym's result is copied instead. */
    void* symbol = dlsym(host->loader, "vkGetInstanceProcAddr");
    CHECK(symbol != NULL);
    if (!symbol) return 0;
    memcpy(&host->get_instance_proc_addr, &symbol, sizeof symbol);

    const char* layer = "VK_LAYER_KHRONOS_validation";
    const char* extension = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    VkApplicationInfo app = {VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "gust C host";
    app.apiVersion = VK_API_VERSION_1_3;
    VkDebugUtilsMessengerCreateInfoEXT messenger = {VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
    messenger.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
    messenger.pfnUserCallback = host_on_message;
    messenger.pUserData = host;
    VkInstanceCreateInfo instance_info = {VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    instance_info.pNext = &messenger;
    instance_info.pApplicationInfo = &app;
    instance_info.enabledLayerCount = 1;
    instance_info.ppEnabledLayerNames = &layer;
    instance_info.enabledExtensionCount = 1;
    instance_info.ppEnabledExtensionNames = &extension;
    CHECK(HOST_LOAD(host, vkCreateInstance)(&instance_info, NULL, &host->instance) == VK_SUCCESS);
    if (!host->instance) return 0;
    CHECK(HOST_LOAD(host, vkCreateDebugUtilsMessengerEXT)(host->instance, &messenger, NULL,
                                                          &host->messenger) == VK_SUCCESS);

    /* The first Vulkan 1.3 device with a graphics and compute queue family. */
    VkPhysicalDevice devices[16];
    uint32_t count = 16;
    HOST_LOAD(host, vkEnumeratePhysicalDevices)(host->instance, &count, devices);
    for (uint32_t d = 0; d < count && !host->physical_device; ++d) {
        VkPhysicalDeviceProperties properties;
        HOST_LOAD(host, vkGetPhysicalDeviceProperties)(devices[d], &properties);
        if (properties.apiVersion < VK_API_VERSION_1_3) continue;
        VkQueueFamilyProperties families[16];
        uint32_t family_count = 16;
        HOST_LOAD(host, vkGetPhysicalDeviceQueueFamilyProperties)(devices[d], &family_count, families);
        for (uint32_t f = 0; f < family_count && !host->physical_device; ++f) {
            if ((families[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) &&
                (families[f].queueFlags & VK_QUEUE_COMPUTE_BIT)) {
                host->physical_device = devices[d];
                host->queue_family = f;
            }
        }
    }
    CHECK(host->physical_device != VK_NULL_HANDLE);
    if (!host->physical_device) return 0;

    VkPhysicalDeviceVulkan13Features features13 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features features12 = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    features12.pNext = &features13;
    VkPhysicalDeviceFeatures2 features = {VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    features.pNext = &features12;
    CHECK_FREE_RESULT(gust_add_required_features(&features), GUST_OK);
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue = {VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue.queueFamilyIndex = host->queue_family;
    queue.queueCount = 1;
    queue.pQueuePriorities = &priority;
    VkDeviceCreateInfo device_info = {VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.pNext = &features;
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue;
    CHECK(HOST_LOAD(host, vkCreateDevice)(host->physical_device, &device_info, NULL, &host->device) ==
          VK_SUCCESS);
    if (!host->device) return 0;
    HOST_LOAD(host, vkGetDeviceQueue)(host->device, host->queue_family, 0, &host->queue);
    return 1;
}

static void host_stop(host_engine* host) {
    if (host->device) HOST_LOAD(host, vkDestroyDevice)(host->device, NULL);
    if (host->messenger)
        HOST_LOAD(host, vkDestroyDebugUtilsMessengerEXT)(host->instance, host->messenger, NULL);
    if (host->instance) HOST_LOAD(host, vkDestroyInstance)(host->instance, NULL);
    if (host->loader) dlclose(host->loader);
}

/* A host-visible buffer the host fills with `bytes` of `data` (usable as a transfer source). */
typedef struct host_buffer {
    VkBuffer buffer;
    VkDeviceMemory memory;
} host_buffer;

static host_buffer host_buffer_create(host_engine* host, const void* data, VkDeviceSize bytes) {
    host_buffer out = {VK_NULL_HANDLE, VK_NULL_HANDLE};
    VkBufferCreateInfo info = {VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = bytes;
    info.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
    info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
    CHECK(HOST_LOAD(host, vkCreateBuffer)(host->device, &info, NULL, &out.buffer) == VK_SUCCESS);
    VkMemoryRequirements needs;
    HOST_LOAD(host, vkGetBufferMemoryRequirements)(host->device, out.buffer, &needs);
    VkPhysicalDeviceMemoryProperties memory;
    HOST_LOAD(host, vkGetPhysicalDeviceMemoryProperties)(host->physical_device, &memory);
    const VkMemoryPropertyFlags wanted =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    uint32_t type = UINT32_MAX;
    for (uint32_t t = 0; t < memory.memoryTypeCount && type == UINT32_MAX; ++t)
        if ((needs.memoryTypeBits & (1u << t)) && (memory.memoryTypes[t].propertyFlags & wanted) == wanted)
            type = t;
    CHECK(type != UINT32_MAX);
    VkMemoryAllocateInfo allocate = {VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    allocate.allocationSize = needs.size;
    allocate.memoryTypeIndex = type;
    CHECK(HOST_LOAD(host, vkAllocateMemory)(host->device, &allocate, NULL, &out.memory) == VK_SUCCESS);
    CHECK(HOST_LOAD(host, vkBindBufferMemory)(host->device, out.buffer, out.memory, 0) == VK_SUCCESS);
    void* mapped = NULL;
    CHECK(HOST_LOAD(host, vkMapMemory)(host->device, out.memory, 0, bytes, 0, &mapped) == VK_SUCCESS);
    if (mapped) memcpy(mapped, data, (size_t)bytes);
    HOST_LOAD(host, vkUnmapMemory)(host->device, out.memory);
    return out;
}

static void host_buffer_destroy(host_engine* host, host_buffer* buffer) {
    HOST_LOAD(host, vkDestroyBuffer)(host->device, buffer->buffer, NULL);
    HOST_LOAD(host, vkFreeMemory)(host->device, buffer->memory, NULL);
}

/* Records one gust_system_step_commands into a one-time command buffer and runs it on the host's queue,
 * waiting for it: one frame in flight. */
static void host_step(host_engine* host, gust_system system) {
    VkCommandPoolCreateInfo pool_info = {VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.queueFamilyIndex = host->queue_family;
    VkCommandPool pool = VK_NULL_HANDLE;
    CHECK(HOST_LOAD(host, vkCreateCommandPool)(host->device, &pool_info, NULL, &pool) == VK_SUCCESS);
    VkCommandBufferAllocateInfo allocate = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    allocate.commandPool = pool;
    allocate.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    allocate.commandBufferCount = 1;
    VkCommandBuffer commands = VK_NULL_HANDLE;
    CHECK(HOST_LOAD(host, vkAllocateCommandBuffers)(host->device, &allocate, &commands) == VK_SUCCESS);
    VkCommandBufferBeginInfo begin = {VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    CHECK(HOST_LOAD(host, vkBeginCommandBuffer)(commands, &begin) == VK_SUCCESS);
    CHECK_RESULT(system, gust_system_step_commands(system, 0.05f, commands), GUST_OK);
    CHECK(HOST_LOAD(host, vkEndCommandBuffer)(commands) == VK_SUCCESS);
    VkSubmitInfo submit = {VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &commands;
    CHECK(HOST_LOAD(host, vkQueueSubmit)(host->queue, 1, &submit, VK_NULL_HANDLE) == VK_SUCCESS);
    CHECK(HOST_LOAD(host, vkQueueWaitIdle)(host->queue) == VK_SUCCESS);
    HOST_LOAD(host, vkDestroyCommandPool)(host->device, pool, NULL);
}

static void runs_on_a_host_device_with_host_commands(void) {
    host_engine host;
    if (!host_start(&host)) {
        host_stop(&host);
        return;
    }
    hook_counts counts = {0};
    gust_system_desc desc = small_world_desc(&counts);
    /* Nothing listed: lavapipe has no optional extension, and gust must not use one the host did not enable.
     */
    const gust_host_device device = {host.instance,
                                     host.physical_device,
                                     host.device,
                                     host.queue_family,
                                     0,
                                     host.get_instance_proc_addr,
                                     NULL,
                                     NULL,
                                     0};
    desc.host = &device;
    desc.submission = GUST_SUBMISSION_HOST_COMMANDS;
    desc.frames_in_flight = 1;
    gust_system system = NULL;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_OK);
    if (system) {
        /* gust submits to the host's family, which has graphics (the test's host picked such a family). */
        gust_queue_info queue = {UINT32_MAX, true};
        CHECK_RESULT(system, gust_system_queue_info(system, &queue), GUST_OK);
        CHECK(queue.family == host.queue_family && !queue.async_compute);
        /* A skinned mesh posed as the 2 m box, then as a 4 m box from the host's vertex buffer: the voxels
         * show the buffer was copied. */
        gust_mesh_desc mesh_desc = box_desc();
        mesh_desc.deforming = true;
        gust_mesh skinned = 0;
        CHECK_RESULT(system, gust_system_create_mesh(system, &mesh_desc, &skinned), GUST_OK);
        float transform[16];
        scale_translate(transform, 1.0f, vec3(0.0f, 4.0f, 0.0f));
        gust_instance instance = 0;
        CHECK_RESULT(system, gust_system_create_instance(system, skinned, transform, true, &instance),
                     GUST_OK);
        CHECK_RESULT(system, gust_system_set_ambient(system, kAmbient), GUST_OK);
        CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_ERROR_INVALID_ARGUMENT);
        /* With one frame in flight, a step's stats are those of the frame recorded by the step before. */
        host_step(&host, system);
        host_step(&host, system);
        gust_frame_stats before;
        CHECK_RESULT(system, gust_system_stats(system, &before), GUST_OK);

        float doubled[8 * 3];
        for (int v = 0; v < 8; ++v)
            for (int a = 0; a < 3; ++a)
                doubled[3 * v + a] = 2.0f * kBoxPositions[4 * v + a];
        host_buffer vertices = host_buffer_create(&host, doubled, sizeof doubled);
        CHECK_RESULT(system, gust_system_set_vertices_buffer(system, skinned, vertices.buffer, 2, 8, false),
                     GUST_ERROR_INVALID_ARGUMENT);
        CHECK_RESULT(system, gust_system_set_vertices_buffer(system, skinned, vertices.buffer, 0, 9, false),
                     GUST_ERROR_INVALID_ARGUMENT);
        CHECK_RESULT(system, gust_system_set_vertices_buffer(system, skinned, vertices.buffer, 0, 8, false),
                     GUST_OK);
        host_step(&host, system);
        host_step(&host, system);
        gust_frame_stats after;
        CHECK_RESULT(system, gust_system_stats(system, &after), GUST_OK);
        /* As in simulates_a_small_world: (n + 2)^3 - (n - 2)^3 voxels for n = 8, then n = 16. */
        CHECK(before.voxels == 10 * 10 * 10 - 6 * 6 * 6);
        CHECK(after.voxels == 18 * 18 * 18 - 14 * 14 * 14);

        CHECK_RESULT(system, gust_system_step_commands(system, 0.05f, VK_NULL_HANDLE),
                     GUST_ERROR_INVALID_ARGUMENT);
        gust_vec3 outside = vec3(100.0f, 4.0f, 0.0f), velocity;
        CHECK_RESULT(system, gust_system_query(system, &outside, 1, &velocity), GUST_OK);
        CHECK(equal3(velocity, kAmbient));

        CHECK_RESULT(system, gust_system_destroy(system), GUST_OK);
        host_buffer_destroy(&host, &vertices);
    }
    CHECK(counts.allocations == counts.frees);
    CHECK(atomic_load(&counts.errors) == 0);
    host_stop(&host);
    CHECK(atomic_load(&host.validation_messages) == 0);
}

/* The settings gust_system_desc gained in 0.5, each seen in what it changes: the Jacobi baseline relaxes in
 * blocks of 8 iterations up to max_iterations, past max_cycles (which bounds V-cycles only) and short of a
 * tight tolerance; a hysteresis of 1 coarsens the blocks a box left once they went unreached for more than
 * one step (the default of 8 keeps them past the last step here); no advection runs; a box created in motion
 * pushes still air in its first step; and the pipeline cache file is written when the system is destroyed. */
static void takes_the_pressure_solver_advection_hysteresis_and_pipeline_cache(void) {
    const char* cache = "gust_c_api_pipelines.bin";
    remove(cache);
    hook_counts counts = {0};
    gust_system_desc desc = small_world_desc(&counts);
    desc.wind.pressure = GUST_PRESSURE_JACOBI;
    desc.wind.max_iterations = 16;
    desc.wind.max_cycles = 1;
    desc.wind.tolerance = 1e-7f;
    desc.wind.advection = GUST_ADVECTION_NONE;
    desc.domain.hysteresis = 1;
    desc.pipeline_cache = cache;
    gust_system system = NULL;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_OK);
    if (!system) return;
    gust_mesh box = 0;
    gust_mesh_desc mesh = box_desc();
    CHECK_RESULT(system, gust_system_create_mesh(system, &mesh, &box), GUST_OK);
    float transform[16], previous[16];
    scale_translate(transform, 1.0f, vec3(-4.5f, 4.0f, 0.0f));
    scale_translate(previous, 1.0f, vec3(-5.0f, 4.0f, 0.0f)); /* 0.5 m in one 0.05 s step: 10 m/s */
    gust_instance mover = 0;
    CHECK_RESULT(system, gust_system_create_moving_instance(system, box, transform, previous, &mover),
                 GUST_OK);
    CHECK(mover != 0);
    gust_frame_stats stats;
    int first_coarsened = -1;
    for (int step = 0; step < 5; ++step) {
        if (step == 1) {
            /* Into the other half of the tree (level-1 nodes are 4 m across): the blocks at x = -4.5 m go
             * stale. */
            scale_translate(transform, 1.0f, vec3(4.5f, 4.0f, 0.0f));
            CHECK_RESULT(system, gust_system_set_transform(system, mover, transform, true), GUST_OK);
        }
        CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
        CHECK_RESULT(system, gust_system_stats(system, &stats), GUST_OK);
        if (step == 0) CHECK(stats.divergence_before > 1.0f); /* the moving surface against still air */
        CHECK(stats.cycles == 16);
        CHECK(!stats.converged);
        CHECK(stats.submissions == 1 && stats.waits == 1);
        if (first_coarsened < 0 && stats.coarsened > 0) first_coarsened = step;
    }
    /* Last reached at step 0, unreached for more than one step at step 2. */
    CHECK(first_coarsened == 2);
    FILE* file = fopen(cache, "rb");
    CHECK(file == NULL); /* written when the system is destroyed */
    if (file) fclose(file);
    CHECK_RESULT(system, gust_system_destroy(system), GUST_OK);
    CHECK(atomic_load(&counts.errors) == 0);
    CHECK(counts.allocations == counts.frees);
    file = fopen(cache, "rb");
    CHECK(file != NULL);
    if (file) {
        CHECK(fseek(file, 0, SEEK_END) == 0 && ftell(file) > 0);
        fclose(file);
    }
    remove(cache);
}

/* gust_system_sample answers from the CPU snapshot, of two cascades here, each with its texture; a reader's
 * failure message is kept per thread. */
static void samples_the_snapshot(void) {
    hook_counts counts = {0};
    gust_system_desc desc = small_world_desc(&counts);
    desc.snapshot = true;
    desc.domain.cascades = 2;
    desc.domain.ratio = 2;
    gust_system system = NULL;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_OK);
    const gust_vec3 points[2] = {{0.0f, 4.0f, 0.0f}, {500.0f, 4.0f, 0.0f}};
    gust_vec3 out[2];
    uint64_t frame = 7;
    CHECK_FREE_RESULT(gust_system_sample(system, points, 2, out, &frame), GUST_ERROR_NOT_READY);
    CHECK(frame == 0);
    CHECK_RESULT(system, gust_system_set_ambient(system, vec3(2.0f, 0.0f, 0.0f)), GUST_OK);
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    CHECK_FREE_RESULT(gust_system_sample(system, points, 2, out, &frame), GUST_OK);
    CHECK(frame == 1);
    CHECK(out[1].x == 2.0f && out[1].y == 0.0f && out[1].z == 0.0f);
    /* The coarser cascade: 16x8x16 cells of 2 m around the same centre, (0, 4, 0). */
    gust_wind_texture coarse;
    CHECK_RESULT(system, gust_system_cascade_texture(system, 1, &coarse), GUST_OK);
    CHECK(coarse.extent[0] == 16 && coarse.extent[1] == 8 && coarse.extent[2] == 16);
    CHECK(near3(transform_point(coarse.world_to_texture, vec3(-16.0f, -4.0f, -16.0f)), vec3(0.0f, 0.0f, 0.0f),
                1e-6f));
    CHECK(near3(transform_point(coarse.world_to_texture, vec3(16.0f, 12.0f, 16.0f)), vec3(1.0f, 1.0f, 1.0f),
                1e-6f));
    CHECK_RESULT(system, gust_system_cascade_texture(system, 2, &coarse), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_FREE_RESULT(gust_system_sample(system, NULL, 2, out, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_FREE_RESULT(gust_system_sample(system, points, 2, NULL, NULL), GUST_ERROR_INVALID_ARGUMENT);
    CHECK_FREE_RESULT(gust_system_sample(NULL, points, 2, out, NULL), GUST_ERROR_INVALID_HANDLE);
    CHECK_FREE_RESULT(gust_system_sample(system, NULL, 0, NULL, NULL), GUST_OK);
    CHECK_RESULT(system, gust_system_destroy(system), GUST_OK);
    /* With the snapshot off no step will ever publish one: a wrong setup, not an answer to wait for. */
    desc.snapshot = false;
    CHECK_FREE_RESULT(gust_system_create(&desc, &system), GUST_OK);
    CHECK_RESULT(system, gust_system_step(system, 0.05f), GUST_OK);
    CHECK_FREE_RESULT(gust_system_sample(system, points, 2, out, NULL), GUST_ERROR_NOT_ENABLED);
    CHECK(strstr(gust_last_create_error(), "snapshot") != NULL);
    CHECK_RESULT(system, gust_system_destroy(system), GUST_OK);
    CHECK(atomic_load(&counts.errors) == 0);
}

int main(void) {
    reports_its_version_and_device_requirements();
    fills_the_documented_defaults();
    rejects_bad_creation_without_touching_the_device();
    simulates_a_small_world();
    takes_the_pressure_solver_advection_hysteresis_and_pipeline_cache();
    runs_on_a_host_device_with_host_commands();
    samples_the_snapshot();
    if (g_failures > 0) {
        fprintf(stderr, "%d check(s) failed\n", g_failures);
        return 1;
    }
    printf("gust C API: all checks passed\n");
    return 0;
}
