// GustWind3D and GustEmitter3D (docs/godot.md, "GustWind3D" and "GustEmitter3D"): the scene translated into
// wind_host calls every physics frame, the wind handed back through sample_wind and a Texture3D per cascade.
#include "nodes.hpp"

#include "../../godot/src/wind_host.hpp"
#include "classdb.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <deque>
#include <dlfcn.h>
#include <map>
#include <mutex>
#include <set>
#include <shared_mutex>
#include <unistd.h>

namespace gust::godot4 {

namespace {

using integration::WindField;
using integration::WindHost;
using integration::WindHostConfig;

constexpr const char* kWind = "GustWind3D";
constexpr const char* kEmitter = "GustEmitter3D";
constexpr std::int64_t kArrayVertex = 0;           // Mesh.ARRAY_VERTEX
constexpr std::int64_t kArrayBones = 10;           // Mesh.ARRAY_BONES: bone (bind) indices a vertex
constexpr std::int64_t kArrayWeights = 11;         // Mesh.ARRAY_WEIGHTS
constexpr std::int64_t kArrayIndex = 12;           // Mesh.ARRAY_INDEX
constexpr std::int64_t kArrayFormatBones = 1024;   // Mesh.ARRAY_FORMAT_BONES
constexpr std::int64_t kArrayFormatWeights = 2048; // Mesh.ARRAY_FORMAT_WEIGHTS
constexpr std::int64_t kImageFormatRgbaf = 11;     // Image.FORMAT_RGBAF
constexpr std::int64_t kGlobalSampler3D = 26;      // RenderingServer.GLOBAL_VAR_TYPE_SAMPLER3D
constexpr std::int64_t kGlobalTransform = 23;      // RenderingServer.GLOBAL_VAR_TYPE_TRANSFORM (mat4)
constexpr std::int64_t kDriverDevice = 0;          // RenderingDevice.DRIVER_RESOURCE_LOGICAL_DEVICE
constexpr std::int64_t kDriverPhysicalDevice = 1;  // DRIVER_RESOURCE_PHYSICAL_DEVICE
constexpr std::int64_t kDriverInstance = 2;        // DRIVER_RESOURCE_TOPMOST_OBJECT
constexpr std::int64_t kTextureType3D = 2;         // RenderingDevice.TEXTURE_TYPE_3D
constexpr std::int64_t kFormatRgba16f = 96;        // RenderingDevice.DATA_FORMAT_R16G16B16A16_SFLOAT
// TEXTURE_USAGE_SAMPLING_BIT | CAN_COPY_FROM_BIT | CAN_COPY_TO_BIT: what gust made its wind images with
// (sampled, transfer source and destination), as texture_create_from_extension must be told.
constexpr std::int64_t kSharedUsage = 1 | 128 | 256;
constexpr const char* kTextureParameter = "gust_wind_texture";
constexpr const char* kTransformParameter = "gust_world_to_texture";
// Exported copies of each cascade's wind image (SystemDesc::exported_copies): Godot's RenderingDevice keeps
// max(3, frame_queue_size) frames (rendering/rendering_device/vsync/frame_queue_size: 2 by default, 2 to 3),
// waiting for a frame's fence before it records that frame again, so at most 3 frames in flight each sample
// the copy published before they were drawn, and gust writes a fourth.
constexpr std::uint32_t kCopies = 4;

// GustEmitter3D.kind, in its enum's order.
constexpr WindEmitterType kKinds[] = {WindEmitterType::Directional, WindEmitterType::Omni,
                                      WindEmitterType::Vortex, WindEmitterType::ConeMotor};

struct Emitter final : Instance {
    std::int64_t kind = 3; // a cone: a fan
    double strength = 5.0; // m/s
    double radius = 1.0;   // m
};

// The emitters in the tree by their Godot object, for the wind node that finds them among its children.
struct EmitterRegistry {
    std::mutex mutex;
    std::map<GDExtensionObjectPtr, Emitter*> emitters;
};
EmitterRegistry& emitter_registry() {
    static EmitterRegistry r;
    return r;
}

// Godot's Vulkan device, as the node imports gust's exported copies into it.
struct GodotVulkan {
    VkDevice device = VK_NULL_HANDLE;
    std::uint8_t uuid[VK_UUID_SIZE] = {}; // its physical device's deviceUUID, for gust's own device
    PFN_vkCreateImage create_image = nullptr;
    PFN_vkDestroyImage destroy_image = nullptr;
    PFN_vkAllocateMemory allocate_memory = nullptr;
    PFN_vkFreeMemory free_memory = nullptr;
    PFN_vkBindImageMemory bind_image_memory = nullptr;
    PFN_vkDeviceWaitIdle device_wait_idle = nullptr;
};

// One exported copy imported into Godot's device: gust's memory, Godot's VkImage on it, Godot's RD texture.
struct ImportedCopy {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    std::uint64_t rid = 0; // texture_create_from_extension
};

// One cascade's texture and where it lies.
struct CascadeTexture {
    Variant texture;                  // ImageTexture3D, or Texture3DRD over the copy gust wrote last
    Transform3D to_texture{};         // world m to the texture's 0..1
    std::vector<ImportedCopy> copies; // shared: kCopies of them
};

// A skinned obstacle's gust mesh and what it was made from (a change of any uploads it again).
struct Skinned {
    std::uint64_t mesh = 0, skin = 0, skeleton = 0; // instance ids; skin 0: Godot's default skin
    std::size_t joints = 0;
    std::uint64_t key = 0; // gust's mesh key
    bool refused = false;  // gust refused it (logged): taken in its rest pose until something changes
    bool seen = false;     // reported this frame
};

struct Wind final : Instance {
    WindHostConfig config;
    Variant group = Variant::from(StringName("gust_obstacles"));
    // sample_wind runs on any thread: the host's lifetime and the ambient wind it falls back to are guarded;
    // everything else is the main thread's (Godot's physics frames and property setters).
    mutable std::shared_mutex mutex;
    WindHost host;
    Vec3 ambient{};
    bool in_tree = false;
    bool dirty = true; // the System must be (re)made from config at the next physics frame
    // Share the wind images with Godot's device where it has one (share_wind_image): gust runs on a device
    // of its own and never submits on a queue of Godot's; Godot samples gust's copies (docs/godot.md).
    bool share = true;
    std::vector<CascadeTexture> textures;
    WindField field;
    std::uint64_t cpu_bytes_last_frame = 0;
    // Godot's RenderingDevice while Godot samples gust's wind images (Forward+, Mobile), and its device; null
    // where the textures are filled through the CPU (headless, Compatibility, share_wind_image off).
    GDExtensionObjectPtr rd = nullptr;
    GodotVulkan vk;
    std::uint32_t slot = 0;                   // the exported copy the last step wrote
    std::int64_t slot_frame = -1;             // Engine.get_frames_drawn() when it was chosen
    std::set<std::string> reported;           // errors already in the log, each printed once
    std::map<std::uint64_t, Skinned> skinned; // by MeshInstance3D
    // Skinned meshes are the node's own, not shared by Mesh resource: their keys have the top bit set, apart
    // from Godot's instance ids, which key the shared static meshes.
    std::uint64_t next_skinned_key = std::uint64_t(1) << 63;
};

Wind& wind(Instance& i) {
    return static_cast<Wind&>(i);
}
Emitter& emitter(Instance& i) {
    return static_cast<Emitter&>(i);
}

void report_once(Wind& w, const std::string& message) {
    if (w.reported.insert(message).second) {
        GUST_GODOT_ERROR(std::string(kWind) + ": " + message);
    }
}

Transform3D global_transform(GDExtensionObjectPtr node) {
    Transform3D t;
    methods.get_global_transform(node).to(GDEXTENSION_VARIANT_TYPE_TRANSFORM3D, &t);
    return t;
}

Array to_array(const Variant& v) {
    Array a;
    if (v.type() == GDEXTENSION_VARIANT_TYPE_ARRAY) {
        v.to(GDEXTENSION_VARIANT_TYPE_ARRAY, a.ptr());
    }
    return a;
}

// The world-to-texture transform of a box `cells` wide from `origin`: texture coordinate (world − origin) /
// (cells · cell).
Transform3D world_to_texture(const std::uint32_t cells[3], const Vec3& origin, float cell) {
    Transform3D t;
    const float o[3] = {origin.x, origin.y, origin.z};
    for (int a = 0; a < 3; ++a) {
        const float scale = 1.0f / (float(cells[a]) * cell);
        t.rows[a][a] = scale;
        t.origin[a] = -o[a] * scale;
    }
    return t;
}

// Fills cascade k's texture from `field` (RGBA floats, a slice an Image), making it the first time.
void upload(Wind& w, std::size_t k, const WindField& field) {
    const std::int64_t nx = field.extent[0], ny = field.extent[1], nz = field.extent[2];
    const std::size_t slice = std::size_t(nx * ny) * 4 * sizeof(float);
    Array images;
    for (std::int64_t z = 0; z < nz; ++z) {
        PackedByteArray bytes;
        bytes.resize(std::int64_t(slice));
        std::memcpy(bytes.data(), field.rgba.data() + std::size_t(z) * slice / sizeof(float), slice);
        images.append(methods.image_create_from_data(
            nullptr,
            {Variant::from(nx), Variant::from(ny), Variant::from(false), Variant::from(kImageFormatRgbaf),
             Variant::from(GDEXTENSION_VARIANT_TYPE_PACKED_BYTE_ARRAY, bytes.ptr())}));
    }
    const Variant list = Variant::from(GDEXTENSION_VARIANT_TYPE_ARRAY, images.ptr());
    CascadeTexture& t = w.textures[k];
    if (t.texture.type() == GDEXTENSION_VARIANT_TYPE_NIL) {
        const StringName type("ImageTexture3D");
        t.texture = Variant::from(gd.construct_object(type.ptr()));
        methods.texture3d_create(t.texture.object(),
                                 {Variant::from(kImageFormatRgbaf), Variant::from(nx), Variant::from(ny),
                                  Variant::from(nz), Variant::from(false), list});
    } else {
        methods.texture3d_update(t.texture.object(), {list});
    }
    t.to_texture = world_to_texture(field.extent, field.origin, field.cell_size);
    w.cpu_bytes_last_frame += std::uint64_t(slice) * std::uint64_t(nz);
}

// Every cascade's texture filled with the ambient wind, where the domain will be (before a first step).
void make_textures(Wind& w) {
    w.textures.clear();
    w.textures.resize(w.config.cascades);
    WindField field;
    for (int a = 0; a < 3; ++a) {
        field.extent[a] = w.config.cells[a];
    }
    field.rgba.resize(std::size_t(field.extent[0]) * field.extent[1] * field.extent[2] * 4);
    for (std::size_t c = 0; c < field.rgba.size() / 4; ++c) {
        field.rgba[4 * c + 0] = w.config.ambient.x;
        field.rgba[4 * c + 1] = w.config.ambient.y;
        field.rgba[4 * c + 2] = w.config.ambient.z;
        field.rgba[4 * c + 3] = 1.0f;
    }
    for (std::uint32_t k = 0; k < w.config.cascades; ++k) {
        field.cell_size = w.config.cell_size * std::pow(float(w.config.ratio), float(k));
        field.origin = {w.config.focus.x - 0.5f * float(field.extent[0]) * field.cell_size,
                        w.config.focus.y - 0.5f * float(field.extent[1]) * field.cell_size,
                        w.config.focus.z - 0.5f * float(field.extent[2]) * field.cell_size};
        upload(w, k, field);
    }
}

// Godot's Vulkan device when Godot renders through a RenderingDevice, this is its render thread
// (get_driver_resource answers 0 anywhere else) and the device can import gust's memory (Godot 4.6 enables
// VK_KHR_external_memory_fd where the driver has it): gust then runs on a device of its own on the same
// physical device and Godot samples the copies it exports. False (the textures filled through the CPU)
// otherwise, with the reason in `why` when Godot has a RenderingDevice.
bool godot_vulkan(Wind& w, std::string& why) {
    const StringName server_name("RenderingServer");
    GDExtensionObjectPtr server = gd.global_get_singleton(server_name.ptr());
    GDExtensionObjectPtr rd = server ? methods.get_rendering_device(server).object() : nullptr;
    if (!rd) {
        return false;
    }
    const std::uint64_t no_rid = 0;
    const Variant rid = Variant::from(GDEXTENSION_VARIANT_TYPE_RID, &no_rid);
    const auto resource = [&](std::int64_t which) {
        return std::uint64_t(
            methods.get_driver_resource(rd, {Variant::from(which), rid, Variant::from(std::int64_t(0))})
                .as_int());
    };
    const std::uint64_t instance = resource(kDriverInstance), physical = resource(kDriverPhysicalDevice),
                        device = resource(kDriverDevice);
    if (!instance || !physical || !device) {
        why = "Godot's RenderingDevice gave no Vulkan device (not its render thread?)";
        return false;
    }
    // Godot loaded Vulkan's loader already: the same one answers for its instance.
    void* loader = dlopen("libvulkan.so.1", RTLD_NOW | RTLD_NOLOAD);
    auto gipa = loader ? reinterpret_cast<PFN_vkGetInstanceProcAddr>(dlsym(loader, "vkGetInstanceProcAddr"))
                       : nullptr;
    if (!gipa) {
        why = "no Vulkan loader in the process";
        return false;
    }
    const auto vk_instance = reinterpret_cast<VkInstance>(instance);
    auto gdpa = reinterpret_cast<PFN_vkGetDeviceProcAddr>(gipa(vk_instance, "vkGetDeviceProcAddr"));
    auto properties2 = reinterpret_cast<PFN_vkGetPhysicalDeviceProperties2>(
        gipa(vk_instance, "vkGetPhysicalDeviceProperties2"));
    GodotVulkan vk;
    vk.device = reinterpret_cast<VkDevice>(device);
    // A device returns null for the commands of an extension it was created without.
    if (!gdpa || !properties2 || !gdpa(vk.device, "vkGetMemoryFdKHR")) {
        why = "Godot's Vulkan device lacks VK_KHR_external_memory_fd";
        return false;
    }
    vk.create_image = reinterpret_cast<PFN_vkCreateImage>(gdpa(vk.device, "vkCreateImage"));
    vk.destroy_image = reinterpret_cast<PFN_vkDestroyImage>(gdpa(vk.device, "vkDestroyImage"));
    vk.allocate_memory = reinterpret_cast<PFN_vkAllocateMemory>(gdpa(vk.device, "vkAllocateMemory"));
    vk.free_memory = reinterpret_cast<PFN_vkFreeMemory>(gdpa(vk.device, "vkFreeMemory"));
    vk.bind_image_memory = reinterpret_cast<PFN_vkBindImageMemory>(gdpa(vk.device, "vkBindImageMemory"));
    vk.device_wait_idle = reinterpret_cast<PFN_vkDeviceWaitIdle>(gdpa(vk.device, "vkDeviceWaitIdle"));
    VkPhysicalDeviceIDProperties id{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &id};
    properties2(reinterpret_cast<VkPhysicalDevice>(physical), &p2);
    std::memcpy(vk.uuid, id.deviceUUID, VK_UUID_SIZE);
    w.vk = vk;
    w.rd = rd;
    return true;
}

// Godot's images over gust's exported copies, kept until Godot's frames that may sample them have completed:
// Godot destroys its views of them (free_rid) only when it reuses the frame that last used them.
struct Retired {
    GodotVulkan vk;
    ImportedCopy copy;
    std::int64_t frame = 0; // Engine.get_frames_drawn() when retired
};
std::vector<Retired> retired; // the main thread's

std::int64_t frames_drawn() {
    const StringName engine_name("Engine");
    GDExtensionObjectPtr engine = gd.global_get_singleton(engine_name.ptr());
    return engine ? methods.get_frames_drawn(engine).as_int() : 0;
}

void destroy_copy(const GodotVulkan& vk, const ImportedCopy& c) {
    if (c.image) {
        vk.destroy_image(vk.device, c.image, nullptr);
    }
    if (c.memory) {
        vk.free_memory(vk.device, c.memory, nullptr);
    }
}

// Destroys the retired images Godot's frames are done with: kCopies frames drawn since, more than Godot keeps
// in flight.
void destroy_retired() {
    const std::int64_t now = frames_drawn();
    std::erase_if(retired, [&](const Retired& r) {
        if (now - r.frame < std::int64_t(kCopies)) {
            return false;
        }
        destroy_copy(r.vk, r.copy);
        return true;
    });
}

// Imports cascade k's exported copies into Godot's device and wraps each as an RD texture. False with the
// reason in `why`; what was imported stays in w.textures for release_shared.
bool import_copies(Wind& w, std::size_t k, std::string& why) {
    CascadeTexture& t = w.textures[k];
    for (std::uint32_t s = 0; s < kCopies; ++s) {
        ExportedImage e;
        if (Outcome o = w.host.export_wind_copy(std::uint32_t(k), s, e); !o) {
            why = o.message();
            return false;
        }
        ImportedCopy& c = t.copies.emplace_back();
        VkExternalMemoryImageCreateInfo external;
        const VkImageCreateInfo info = gust::import_image_info(e, external);
        if (VkResult r = w.vk.create_image(w.vk.device, &info, nullptr, &c.image); r != VK_SUCCESS) {
            close(e.fd);
            why = "vkCreateImage on Godot's device failed (" + std::to_string(int(r)) + ")";
            return false;
        }
        VkMemoryDedicatedAllocateInfo dedicated{VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO};
        dedicated.image = c.image;
        VkImportMemoryFdInfoKHR import{VK_STRUCTURE_TYPE_IMPORT_MEMORY_FD_INFO_KHR, &dedicated};
        import.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
        import.fd = e.fd;
        VkMemoryAllocateInfo allocation{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &import};
        allocation.allocationSize = e.allocation_size;
        allocation.memoryTypeIndex = e.memory_type_index;
        if (VkResult r = w.vk.allocate_memory(w.vk.device, &allocation, nullptr, &c.memory);
            r != VK_SUCCESS) {
            close(e.fd); // a failed import leaves the descriptor the caller's
            why = "importing gust's memory into Godot's device failed (" + std::to_string(int(r)) + ")";
            return false;
        }
        if (VkResult r = w.vk.bind_image_memory(w.vk.device, c.image, c.memory, 0); r != VK_SUCCESS) {
            why = "vkBindImageMemory on Godot's device failed (" + std::to_string(int(r)) + ")";
            return false;
        }
        const Variant rid = methods.texture_create_from_extension(
            w.rd, {Variant::from(kTextureType3D), Variant::from(kFormatRgba16f),
                   Variant::from(std::int64_t(0)), Variant::from(kSharedUsage),
                   Variant::from(std::int64_t(reinterpret_cast<std::uintptr_t>(c.image))),
                   Variant::from(std::int64_t(e.extent[0])), Variant::from(std::int64_t(e.extent[1])),
                   Variant::from(std::int64_t(e.extent[2])), Variant::from(std::int64_t(1)),
                   Variant::from(std::int64_t(1))});
        rid.to(GDEXTENSION_VARIANT_TYPE_RID, &c.rid);
        if (!c.rid) {
            why = "texture_create_from_extension refused gust's image";
            return false;
        }
    }
    // One Texture3DRD a cascade for the node's life in the tree: materials holding it see each new copy.
    const StringName type("Texture3DRD");
    t.texture = Variant::from(gd.construct_object(type.ptr()));
    return true;
}

// Whether the global shader parameters were declared in this process (publish_globals).
bool globals_declared = false;

// Frees the RD textures over gust's copies and retires Godot's images of them (destroy_retired) before the
// System goes. Materials may still hold the finest one through the global shader parameter, and would draw
// with a freed image: the parameter is first pointed at a texture of one texel of the ambient wind (Godot's
// placeholder for an empty Texture3DRD is 2D, which a sampler3D must not read).
void release_shared(Wind& w) {
    if (!w.rd || w.textures.empty()) {
        w.textures.clear();
        return;
    }
    const StringName server_name("RenderingServer");
    GDExtensionObjectPtr server = gd.global_get_singleton(server_name.ptr());
    if (server && globals_declared) {
        WindField still;
        still.extent[0] = still.extent[1] = still.extent[2] = 1;
        still.cell_size = 1.0f;
        still.rgba = {w.config.ambient.x, w.config.ambient.y, w.config.ambient.z, 1.0f};
        w.textures.resize(w.textures.size() + 1);
        upload(w, w.textures.size() - 1, still);
        methods.global_shader_parameter_set(
            server, {Variant::from(StringName(kTextureParameter)), w.textures.back().texture});
    }
    const std::int64_t frame = frames_drawn();
    for (CascadeTexture& t : w.textures) {
        for (const ImportedCopy& c : t.copies) {
            if (c.rid) {
                methods.free_rid(w.rd, {Variant::from(GDEXTENSION_VARIANT_TYPE_RID, &c.rid)});
            }
            retired.push_back({w.vk, c, frame});
        }
    }
    w.textures.clear();
}

// Points each cascade's Texture3DRD at a copy of the step just taken. gust writes a copy no frame of Godot's
// in flight samples: the one it wrote last while no frame was drawn since, else the next of kCopies (Godot
// keeps fewer frames in flight). gust's copy waits for its fence, so it is complete before Godot records a
// frame that samples it; Godot's device has no semaphore of gust's to wait on, so the CPU orders the two.
Outcome share_textures(Wind& w) {
    const std::int64_t frame = frames_drawn();
    if (frame != w.slot_frame) {
        w.slot = (w.slot + 1) % kCopies;
        w.slot_frame = frame;
    }
    if (Outcome o = w.host.copy_wind_textures(w.slot); !o) {
        return o;
    }
    const std::span<const WindTexture> images = w.host.wind_textures();
    for (std::size_t k = 0; k < images.size() && k < w.textures.size(); ++k) {
        CascadeTexture& t = w.textures[k];
        for (int r = 0; r < 3; ++r) {
            for (int c = 0; c < 3; ++c) {
                t.to_texture.rows[r][c] = images[k].world_to_texture.m[4 * c + r];
            }
            t.to_texture.origin[r] = images[k].world_to_texture.m[12 + r];
        }
        methods.set_texture_rd_rid(t.texture.object(),
                                   {Variant::from(GDEXTENSION_VARIANT_TYPE_RID, &t.copies[w.slot].rid)});
    }
    return {};
}

// The finest cascade as global shader parameters, so any material can read it. The extension declares them
// once a process (Godot lists its parameters in the editor only): a project must not declare them itself.
void publish_globals(Wind& w) {
    const StringName server_name("RenderingServer");
    GDExtensionObjectPtr server = gd.global_get_singleton(server_name.ptr());
    if (!server || w.textures.empty()) {
        return;
    }
    const CascadeTexture& t = w.textures[0];
    const Variant transform = Variant::from(GDEXTENSION_VARIANT_TYPE_TRANSFORM3D, &t.to_texture);
    const Variant texture_name = Variant::from(StringName(kTextureParameter));
    const Variant transform_name = Variant::from(StringName(kTransformParameter));
    if (!globals_declared) {
        globals_declared = true;
        methods.global_shader_parameter_add(server,
                                            {texture_name, Variant::from(kGlobalSampler3D), t.texture});
        methods.global_shader_parameter_add(server,
                                            {transform_name, Variant::from(kGlobalTransform), transform});
        return;
    }
    methods.global_shader_parameter_set(server, {texture_name, t.texture});
    methods.global_shader_parameter_set(server, {transform_name, transform});
}

// A Mesh's triangles in mesh space, every triangle surface in one list; with `skinned`, also each vertex's 4
// bone indices and weights (ARRAY_BONES and ARRAY_WEIGHTS).
struct MeshArrays {
    std::vector<float> positions;
    std::vector<std::uint32_t> indices;
    std::vector<std::int32_t> joints;
    std::vector<float> weights;
};

// Fills `out` from `mesh`; false with the reason in `why` when it has no triangles or (skinned) a surface
// lacks 4 bone indices and weights a vertex (Godot 4 may have 8: gust takes 4).
bool read_mesh(GDExtensionObjectPtr mesh, bool skinned, MeshArrays& out, std::string& why) {
    const std::int64_t surfaces = methods.get_surface_count(mesh).as_int();
    for (std::int64_t s = 0; s < surfaces; ++s) {
        Array arrays = to_array(methods.surface_get_arrays(mesh, {Variant::from(s)}));
        if (arrays.size() <= kArrayIndex) {
            continue;
        }
        PackedVector3Array vertices;
        static_cast<const Variant*>(arrays.at(kArrayVertex))
            ->to(GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY, vertices.ptr());
        const std::uint32_t base = std::uint32_t(out.positions.size() / 3);
        const Vec3* v = vertices.data();
        const std::int64_t nv = vertices.size();
        for (std::int64_t i = 0; i < nv; ++i) {
            out.positions.insert(out.positions.end(), {v[i].x, v[i].y, v[i].z});
        }
        if (skinned) {
            const auto* bones = static_cast<const Variant*>(arrays.at(kArrayBones));
            const auto* weights = static_cast<const Variant*>(arrays.at(kArrayWeights));
            if (bones->type() != GDEXTENSION_VARIANT_TYPE_PACKED_INT32_ARRAY ||
                weights->type() != GDEXTENSION_VARIANT_TYPE_PACKED_FLOAT32_ARRAY) {
                why = "surface " + std::to_string(s) + " has no bone indices and weights";
                return false;
            }
            PackedInt32Array b;
            PackedFloat32Array wt;
            bones->to(GDEXTENSION_VARIANT_TYPE_PACKED_INT32_ARRAY, b.ptr());
            weights->to(GDEXTENSION_VARIANT_TYPE_PACKED_FLOAT32_ARRAY, wt.ptr());
            if (b.size() != 4 * nv || wt.size() != 4 * nv) {
                why = "surface " + std::to_string(s) + " has " + std::to_string(nv ? b.size() / nv : 0) +
                      " bone indices a vertex, not 4";
                return false;
            }
            out.joints.insert(out.joints.end(), b.data(), b.data() + b.size());
            out.weights.insert(out.weights.end(), wt.data(), wt.data() + wt.size());
        }
        const auto* index_variant = static_cast<const Variant*>(arrays.at(kArrayIndex));
        if (index_variant->type() == GDEXTENSION_VARIANT_TYPE_PACKED_INT32_ARRAY) {
            PackedInt32Array index;
            index_variant->to(GDEXTENSION_VARIANT_TYPE_PACKED_INT32_ARRAY, index.ptr());
            const std::int32_t* x = index.data();
            for (std::int64_t i = 0; i < index.size(); ++i) {
                out.indices.push_back(base + std::uint32_t(x[i]));
            }
        } else {
            for (std::int64_t i = 0; i < nv; ++i) {
                out.indices.push_back(base + std::uint32_t(i));
            }
        }
    }
    if (out.indices.empty()) {
        why = "has no triangles";
        return false;
    }
    return true;
}

Mat4 to_mat4(const Variant& transform) {
    Transform3D t;
    transform.to(GDEXTENSION_VARIANT_TYPE_TRANSFORM3D, &t);
    return godot4::to_mat4(t);
}

// The Skeleton3D a MeshInstance3D's skeleton path leads to, or null.
GDExtensionObjectPtr skeleton_of(GDExtensionObjectPtr node) {
    GDExtensionObjectPtr target = methods.get_node_or_null(node, {methods.get_skeleton_path(node)}).object();
    return is_class(target, "Skeleton3D") ? target : nullptr;
}

// True when some surface of an ArrayMesh carries bone indices and weights (PrimitiveMeshes carry none).
bool has_bone_weights(GDExtensionObjectPtr mesh) {
    if (!is_class(mesh, "ArrayMesh")) {
        return false;
    }
    const std::int64_t surfaces = methods.get_surface_count(mesh).as_int();
    for (std::int64_t s = 0; s < surfaces; ++s) {
        const std::int64_t format = methods.surface_get_format(mesh, {Variant::from(s)}).as_int();
        if ((format & kArrayFormatBones) != 0 && (format & kArrayFormatWeights) != 0) {
            return true;
        }
    }
    return false;
}

// The binds of `skin` on `skeleton` (a bind names its bone, or gives its index), or Godot's default skin from
// the skeleton's rests when the MeshInstance3D has no Skin (Skeleton3D.create_skin_from_rest_transforms).
// False with the reason in `why`.
bool skin_binds(GDExtensionObjectPtr skin, GDExtensionObjectPtr skeleton,
                std::vector<integration::SkinBind>& binds, std::string& why) {
    const std::int64_t bones = methods.get_bone_count(skeleton).as_int();
    if (!skin) {
        std::vector<Mat4> rests(std::size_t(std::max<std::int64_t>(bones, 0)));
        std::vector<std::int32_t> parents(rests.size());
        for (std::size_t i = 0; i < rests.size(); ++i) {
            const Variant bone = Variant::from(std::int64_t(i));
            rests[i] = to_mat4(methods.get_bone_rest(skeleton, {bone}));
            parents[i] = std::int32_t(methods.get_bone_parent(skeleton, {bone}).as_int());
        }
        if (Outcome o = integration::default_skin(rests, parents, binds); !o) {
            why = "the skeleton's default skin: " + o.message();
            return false;
        }
        return true;
    }
    const std::int64_t count = methods.get_bind_count(skin).as_int();
    binds.assign(std::size_t(std::max<std::int64_t>(count, 0)), {});
    for (std::size_t i = 0; i < binds.size(); ++i) {
        const Variant index = Variant::from(std::int64_t(i));
        const Variant name = methods.get_bind_name(skin, {index});
        if (gd.variant_booleanize(name.ptr())) {
            binds[i].bone = std::int32_t(methods.find_bone(skeleton, {name}).as_int());
            if (binds[i].bone < 0) {
                why = "bind " + std::to_string(i) + " names a bone the skeleton lacks";
                return false;
            }
        } else {
            binds[i].bone = std::int32_t(methods.get_bind_bone(skin, {index}).as_int());
        }
        if (binds[i].bone < 0 || binds[i].bone >= bones) {
            why = "bind " + std::to_string(i) + " follows bone " + std::to_string(binds[i].bone) +
                  ", the skeleton has " + std::to_string(bones);
            return false;
        }
        binds[i].pose = to_mat4(methods.get_bind_pose(skin, {index}));
    }
    return true;
}

// A skinned MeshInstance3D: its bind pose and skin uploaded once (again when its Mesh, Skin, Skeleton3D or
// bind count changes), its palette from the skeleton's bone poses every frame, placed by the node's global
// transform (docs/godot.md, "Skinned meshes"). False when gust refuses it (the reason is logged once): the
// caller then takes it in its rest pose.
bool report_skinned(Wind& w, GDExtensionObjectPtr node, std::uint64_t id, GDExtensionObjectPtr mesh,
                    GDExtensionObjectPtr skeleton, GDExtensionObjectPtr skin) {
    auto refuse = [&](const std::string& why) {
        report_once(w,
                    "skinned MeshInstance3D " + std::to_string(id) + ": " + why + ": taken in its rest pose");
        return false;
    };
    std::vector<integration::SkinBind> binds;
    std::string why;
    if (!skin_binds(skin, skeleton, binds, why)) {
        return refuse(why);
    }
    Skinned now;
    now.mesh = gd.object_get_instance_id(mesh);
    now.skin = skin ? gd.object_get_instance_id(skin) : 0;
    now.skeleton = gd.object_get_instance_id(skeleton);
    now.joints = binds.size();
    Skinned& s = w.skinned[id];
    s.seen = true;
    if (s.mesh != now.mesh || s.skin != now.skin || s.skeleton != now.skeleton || s.joints != now.joints) {
        s = now;
        s.seen = true;
        MeshArrays arrays;
        if (!read_mesh(mesh, true, arrays, why)) {
            s.refused = true;
            return refuse("its Mesh " + why);
        }
        const integration::SkinnedMeshData data{
            arrays.positions, arrays.indices, arrays.joints, arrays.weights,
            std::uint32_t(std::min<std::size_t>(binds.size(), 0xffffffffu))};
        const std::uint64_t key = w.next_skinned_key++;
        if (Outcome o = w.host.add_skinned_mesh(key, data); !o) {
            s.refused = true;
            return refuse(o.message());
        }
        s.key = key;
    }
    if (s.refused) {
        return false;
    }
    const std::int64_t bones = methods.get_bone_count(skeleton).as_int();
    std::vector<Mat4> poses(std::size_t(std::max<std::int64_t>(bones, 0)));
    for (std::size_t i = 0; i < poses.size(); ++i) {
        poses[i] = to_mat4(methods.get_bone_global_pose(skeleton, {Variant::from(std::int64_t(i))}));
    }
    std::vector<Mat4> palette;
    Outcome o = integration::skin_palette(poses, binds, palette);
    if (o) {
        o = w.host.set_bones(s.key, palette);
    }
    if (!o) {
        s.refused = true;
        return refuse(o.message());
    }
    if (Outcome r = w.host.report_obstacle(id, s.key, godot4::to_mat4(global_transform(node))); !r) {
        report_once(w, "MeshInstance3D " + std::to_string(id) + ": " + r.message());
    }
    return true;
}

void report_obstacles(Wind& w, GDExtensionObjectPtr tree) {
    Array nodes = to_array(methods.get_nodes_in_group(tree, {w.group}));
    w.host.begin_obstacles();
    for (auto& [id, s] : w.skinned) {
        s.seen = false;
    }
    for (std::int64_t i = 0; i < nodes.size(); ++i) {
        const Variant item(*static_cast<const Variant*>(nodes.at(i)));
        GDExtensionObjectPtr node = item.object();
        const std::uint64_t id = gd.object_get_instance_id(node);
        if (!is_class(node, "MeshInstance3D")) {
            report_once(w, "node " + std::to_string(id) +
                               " of the obstacle group is not a MeshInstance3D: ignored");
            continue;
        }
        const Variant mesh = methods.get_mesh(node);
        if (!mesh.object()) {
            continue;
        }
        GDExtensionObjectPtr skin = methods.get_skin(node).object();
        GDExtensionObjectPtr skeleton = skeleton_of(node);
        if (skeleton && has_bone_weights(mesh.object())) {
            if (report_skinned(w, node, id, mesh.object(), skeleton, skin)) {
                continue;
            }
        } else if (skin) {
            report_once(w, "MeshInstance3D " + std::to_string(id) + " has a Skin but " +
                               (skeleton ? "its Mesh has no bone weights"
                                         : "its skeleton path leads to no Skeleton3D") +
                               ": taken in its rest pose");
        }
        const std::uint64_t mesh_key = gd.object_get_instance_id(mesh.object());
        if (!w.host.has_mesh(mesh_key)) {
            MeshArrays arrays;
            std::string why;
            if (!read_mesh(mesh.object(), false, arrays, why)) {
                report_once(w, "MeshInstance3D " + std::to_string(id) + " " + why + ": ignored");
                continue;
            }
            if (Outcome o = w.host.add_mesh(mesh_key, arrays.positions, arrays.indices); !o) {
                report_once(w, "MeshInstance3D " + std::to_string(id) + ": " + o.message());
                continue;
            }
        }
        if (Outcome o = w.host.report_obstacle(id, mesh_key, godot4::to_mat4(global_transform(node))); !o) {
            report_once(w, "MeshInstance3D " + std::to_string(id) + ": " + o.message());
        }
    }
    w.host.end_obstacles();
    for (auto it = w.skinned.begin(); it != w.skinned.end();) {
        it = it->second.seen ? std::next(it) : w.skinned.erase(it);
    }
}

void report_emitters(Wind& w) {
    std::vector<WindEmitter> emitters;
    Array children = to_array(methods.get_children(w.owner, {Variant::from(false)}));
    std::lock_guard lock(emitter_registry().mutex);
    for (std::int64_t i = 0; i < children.size(); ++i) {
        const Variant child(*static_cast<const Variant*>(children.at(i)));
        auto found = emitter_registry().emitters.find(child.object());
        if (found == emitter_registry().emitters.end()) {
            continue;
        }
        const Emitter& e = *found->second;
        const Transform3D t = global_transform(child.object());
        // Pointing along its -Z: the basis' third column, negated.
        const float dx = -t.rows[0][2], dy = -t.rows[1][2], dz = -t.rows[2][2];
        const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
        if (!(len > 0.0f) || !std::isfinite(len)) {
            continue;
        }
        WindEmitter out;
        out.type = kKinds[e.kind];
        out.position = {t.origin[0], t.origin[1], t.origin[2]};
        out.direction = {dx / len, dy / len, dz / len};
        out.radius = float(e.radius);
        out.strength = float(e.strength);
        // A cone throws its air two radii (docs/godot.md "Godot 4").
        out.length = out.type == WindEmitterType::ConeMotor ? 2.0f * out.radius : 0.0f;
        emitters.push_back(out);
    }
    if (Outcome o = w.host.set_emitters(emitters); !o) {
        report_once(w, "emitters: " + o.message());
    }
}

void tick(Wind& w) {
    GDExtensionObjectPtr tree = methods.get_tree(w.owner).object();
    if (!tree) {
        return;
    }
    const Transform3D t = global_transform(w.owner);
    const Vec3 focus{t.origin[0], t.origin[1], t.origin[2]};
    w.cpu_bytes_last_frame = 0;
    if (w.dirty) {
        w.dirty = false;
        w.config.focus = focus;
        std::unique_lock lock(w.mutex);
        release_shared(w);
        w.host.destroy();
        w.skinned.clear();
        w.rd = nullptr;
        Hooks hooks;
        hooks.log = [](void*, LogLevel level, const char* message) {
            if (level == LogLevel::Error) {
                GUST_GODOT_ERROR(std::string(kWind) + ": " + message);
            }
        };
        std::string why;
        if (w.share && godot_vulkan(w, why)) {
            // gust on a device of its own on Godot's physical device, never on a queue of Godot's: Godot's
            // transfer workers submit on its queues from other threads under a lock extensions cannot take.
            if (Outcome o = w.host.create(w.config, hooks, nullptr, kCopies, w.vk.uuid); !o) {
                why = o.message();
                w.rd = nullptr;
            } else {
                w.textures.resize(w.config.cascades);
                for (std::size_t k = 0; k < w.textures.size() && w.rd; ++k) {
                    if (!import_copies(w, k, why)) {
                        release_shared(w);
                        w.host.destroy();
                        w.rd = nullptr;
                    }
                }
            }
        }
        if (!w.rd && !why.empty()) {
            GUST_GODOT_WARNING(std::string(kWind) + ": cannot share the wind images with Godot's device (" +
                               why + "): the wind textures are filled through the CPU");
        }
        if (!w.rd) {
            if (Outcome o = w.host.create(w.config, hooks); !o) {
                report_once(w, "no wind: " + o.message());
                return;
            }
        }
        lock.unlock();
        w.reported.clear();
        if (!w.rd) {
            make_textures(w);
        } else if (Outcome o = share_textures(w); !o) {
            report_once(w, "wind texture: " + o.message());
        }
    }
    destroy_retired();
    if (!w.host.alive()) {
        return;
    }
    if (Outcome o = w.host.set_focus(focus); !o) {
        report_once(w, "focus: " + o.message());
    }
    report_obstacles(w, tree);
    report_emitters(w);
    double dt = 0.0;
    methods.get_physics_process_delta_time(w.owner).to(GDEXTENSION_VARIANT_TYPE_FLOAT, &dt);
    if (Outcome o = w.host.step(float(dt)); !o) {
        report_once(w, "step: " + o.message());
        return;
    }
    if (w.rd) {
        if (Outcome o = share_textures(w); !o) {
            report_once(w, "wind texture: " + o.message());
            return;
        }
    } else {
        for (std::uint32_t k = 0; k < w.config.cascades; ++k) {
            if (Outcome o = w.host.read_field(w.field, k); !o) {
                report_once(w, "wind texture: " + o.message());
                return;
            }
            upload(w, k, w.field);
        }
    }
    publish_globals(w);
}

void wind_notification(Instance& i, std::int32_t what) {
    Wind& w = wind(i);
    if (what == kNotificationEnterTree) {
        w.in_tree = true;
        w.dirty = true;
        methods.set_physics_process(w.owner, {Variant::from(true)});
    } else if (what == kNotificationExitTree) {
        w.in_tree = false;
        std::unique_lock lock(w.mutex);
        release_shared(w);
        w.host.destroy();
        w.skinned.clear();
        w.rd = nullptr;
    } else if (what == kNotificationPhysicsProcess && w.in_tree) {
        tick(w);
    }
}

// A new configuration takes effect at the next physics frame; an invalid one is refused, named in the log.
void configure(Wind& w, const WindHostConfig& next) {
    if (std::string message = integration::validate(next); !message.empty()) {
        GUST_GODOT_ERROR(std::string(kWind) + "." + message);
        return;
    }
    w.config = next;
    w.dirty = true;
}

Variant set_cells(Instance& i, const Variant* args) {
    std::int32_t v[3] = {};
    args[0].to(GDEXTENSION_VARIANT_TYPE_VECTOR3I, v);
    WindHostConfig next = wind(i).config;
    for (int a = 0; a < 3; ++a) {
        next.cells[a] = v[a] < 0 ? 0u : std::uint32_t(v[a]);
    }
    configure(wind(i), next);
    return {};
}
Variant get_cells(Instance& i, const Variant*) {
    const std::int32_t v[3] = {std::int32_t(wind(i).config.cells[0]), std::int32_t(wind(i).config.cells[1]),
                               std::int32_t(wind(i).config.cells[2])};
    return Variant::from(GDEXTENSION_VARIANT_TYPE_VECTOR3I, v);
}
Variant set_cell_size(Instance& i, const Variant* args) {
    double v = 0.0;
    args[0].to(GDEXTENSION_VARIANT_TYPE_FLOAT, &v);
    WindHostConfig next = wind(i).config;
    next.cell_size = float(v);
    configure(wind(i), next);
    return {};
}
Variant get_cell_size(Instance& i, const Variant*) {
    return Variant::from(double(wind(i).config.cell_size));
}
Variant set_cascades(Instance& i, const Variant* args) {
    WindHostConfig next = wind(i).config;
    const std::int64_t v = args[0].as_int();
    next.cascades = v < 0 || v > 1000 ? 0u : std::uint32_t(v);
    configure(wind(i), next);
    return {};
}
Variant get_cascades(Instance& i, const Variant*) {
    return Variant::from(std::int64_t(wind(i).config.cascades));
}
Variant set_ratio(Instance& i, const Variant* args) {
    WindHostConfig next = wind(i).config;
    const std::int64_t v = args[0].as_int();
    next.ratio = v < 0 || v > 1000 ? 0u : std::uint32_t(v);
    configure(wind(i), next);
    return {};
}
Variant get_ratio(Instance& i, const Variant*) {
    return Variant::from(std::int64_t(wind(i).config.ratio));
}
Variant set_ambient_wind(Instance& i, const Variant* args) {
    Wind& w = wind(i);
    Vec3 v{};
    args[0].to(GDEXTENSION_VARIANT_TYPE_VECTOR3, &v);
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
        GUST_GODOT_ERROR(std::string(kWind) + ".ambient_wind must be finite (m/s)");
        return {};
    }
    std::unique_lock lock(w.mutex);
    w.config.ambient = v;
    w.ambient = v;
    if (Outcome o = w.host.set_ambient(v); !o) {
        GUST_GODOT_ERROR(std::string(kWind) + ".ambient_wind: " + o.message());
    }
    return {};
}
Variant get_ambient_wind(Instance& i, const Variant*) {
    return Variant::from(wind(i).config.ambient);
}
Variant set_share_wind_image(Instance& i, const Variant* args) {
    Wind& w = wind(i);
    GDExtensionBool v = false;
    args[0].to(GDEXTENSION_VARIANT_TYPE_BOOL, &v);
    if (w.share != bool(v)) {
        w.share = v;
        w.dirty = true;
    }
    return {};
}
Variant get_share_wind_image(Instance& i, const Variant*) {
    return Variant::from(wind(i).share);
}
Variant set_obstacle_group(Instance& i, const Variant* args) {
    wind(i).group = args[0];
    return {};
}
Variant get_obstacle_group(Instance& i, const Variant*) {
    return wind(i).group;
}

Variant sample_wind(Instance& i, const Variant* args) {
    const Wind& w = wind(i);
    PackedVector3Array points, velocities;
    args[0].to(GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY, points.ptr());
    const std::int64_t n = points.size();
    velocities.resize(n);
    if (n > 0) {
        std::shared_lock lock(w.mutex);
        w.host.sample({points.data(), std::size_t(n)}, {velocities.data(), std::size_t(n)}, w.ambient);
    }
    return Variant::from(GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY, velocities.ptr());
}

bool cascade_of(const Wind& w, const Variant& arg, std::size_t& k) {
    const std::int64_t c = arg.as_int();
    if (c < 0 || std::size_t(c) >= w.textures.size()) {
        GUST_GODOT_ERROR(std::string(kWind) + ": cascade " + std::to_string(c) + " has no texture (" +
                         std::to_string(w.textures.size()) +
                         " cascades; none before the node enters the tree)");
        return false;
    }
    k = std::size_t(c);
    return true;
}

Variant get_wind_texture(Instance& i, const Variant* args) {
    std::size_t k = 0;
    return cascade_of(wind(i), args[0], k) ? wind(i).textures[k].texture : Variant();
}

Variant get_world_to_texture(Instance& i, const Variant* args) {
    const Wind& w = wind(i);
    std::size_t k = 0;
    const Transform3D t = cascade_of(w, args[0], k) ? w.textures[k].to_texture : Transform3D{};
    return Variant::from(GDEXTENSION_VARIANT_TYPE_TRANSFORM3D, &t);
}

Variant get_stats(Instance& i, const Variant*) {
    const Wind& w = wind(i);
    Dictionary d;
    d.set("steps", Variant::from(std::int64_t(w.host.steps())));
    d.set("step_ms", Variant::from(w.host.last_step_ms()));
    d.set("texture_bytes_through_cpu", Variant::from(std::int64_t(w.cpu_bytes_last_frame)));
    d.set("shares_wind_image", Variant::from(w.rd != nullptr));
    const std::string device = w.host.device_name();
    const String name(device.c_str());
    d.set("device", Variant::from(GDEXTENSION_VARIANT_TYPE_STRING, name.ptr()));
    return Variant::from(GDEXTENSION_VARIANT_TYPE_DICTIONARY, d.ptr());
}

void emitter_notification(Instance& i, std::int32_t what) {
    EmitterRegistry& r = emitter_registry();
    std::lock_guard lock(r.mutex);
    if (what == kNotificationEnterTree) {
        r.emitters[i.owner] = &emitter(i);
    } else if (what == kNotificationExitTree) {
        r.emitters.erase(i.owner);
    }
}

Variant set_kind(Instance& i, const Variant* args) {
    const std::int64_t v = args[0].as_int();
    if (v < 0 || v > 3) {
        GUST_GODOT_ERROR(std::string(kEmitter) + ".kind = " + std::to_string(v) +
                         ": must be 0 (directional), 1 (omni), 2 (vortex) or 3 (cone)");
        return {};
    }
    emitter(i).kind = v;
    return {};
}
Variant get_kind(Instance& i, const Variant*) {
    return Variant::from(emitter(i).kind);
}
Variant set_strength(Instance& i, const Variant* args) {
    double v = 0.0;
    args[0].to(GDEXTENSION_VARIANT_TYPE_FLOAT, &v);
    if (!std::isfinite(v)) {
        GUST_GODOT_ERROR(std::string(kEmitter) + ".strength must be finite (m/s)");
        return {};
    }
    emitter(i).strength = v;
    return {};
}
Variant get_strength(Instance& i, const Variant*) {
    return Variant::from(emitter(i).strength);
}
Variant set_radius(Instance& i, const Variant* args) {
    double v = 0.0;
    args[0].to(GDEXTENSION_VARIANT_TYPE_FLOAT, &v);
    if (!(std::isfinite(v) && v > 0.0)) {
        GUST_GODOT_ERROR(std::string(kEmitter) + ".radius = " + std::to_string(v) +
                         ": must be a length > 0 m");
        return {};
    }
    emitter(i).radius = v;
    return {};
}
Variant get_radius(Instance& i, const Variant*) {
    return Variant::from(emitter(i).radius);
}

// A property with its two methods.
void property(const char* cls, Slot slot, MethodBody setter, MethodBody getter, std::uint32_t hint = 0,
              const char* hint_string = "") {
    const std::string set = std::string("set_") + slot.name, get = std::string("get_") + slot.name;
    // ClassDB copies the names: these strings need only outlive the calls, the MethodSpecs keep theirs.
    static std::deque<std::string> names;
    const char* set_name = names.emplace_back(set).c_str();
    const char* get_name = names.emplace_back(get).c_str();
    register_method(cls, {set_name, setter, {}, {slot}, {}, false});
    register_method(cls, {get_name, getter, slot, {}, {}, true});
    register_property(cls, slot, set_name, get_name, hint, hint_string);
}

} // namespace

void release_godot_images() {
    // Godot's frames have ended (the extension is deinitialized after the main loop, before Godot's
    // RenderingDevice goes), and nothing else submits now: wait for Godot's device once, then destroy.
    if (!retired.empty()) {
        retired.front().vk.device_wait_idle(retired.front().vk.device);
    }
    for (const Retired& r : retired) {
        destroy_copy(r.vk, r.copy);
    }
    retired.clear();
}

void register_nodes() {
    register_class({kWind, "Node3D", []() -> Instance* { return new Wind(); }, wind_notification});
    property(kWind, {"cells", GDEXTENSION_VARIANT_TYPE_VECTOR3I}, set_cells, get_cells);
    property(kWind, {"cell_size", GDEXTENSION_VARIANT_TYPE_FLOAT}, set_cell_size, get_cell_size);
    property(kWind, {"cascades", GDEXTENSION_VARIANT_TYPE_INT}, set_cascades, get_cascades);
    property(kWind, {"ratio", GDEXTENSION_VARIANT_TYPE_INT}, set_ratio, get_ratio);
    property(kWind, {"ambient_wind", GDEXTENSION_VARIANT_TYPE_VECTOR3}, set_ambient_wind, get_ambient_wind);
    property(kWind, {"share_wind_image", GDEXTENSION_VARIANT_TYPE_BOOL}, set_share_wind_image,
             get_share_wind_image);
    property(kWind, {"obstacle_group", GDEXTENSION_VARIANT_TYPE_STRING_NAME}, set_obstacle_group,
             get_obstacle_group);
    const Slot points{"points", GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY};
    const Slot cascade{"cascade", GDEXTENSION_VARIANT_TYPE_INT};
    register_method(kWind, {"sample_wind", sample_wind, points, {points}, {}, true});
    register_method(kWind, {"get_wind_texture",
                            get_wind_texture,
                            {"", GDEXTENSION_VARIANT_TYPE_OBJECT, "Texture3D"},
                            {cascade},
                            {Variant::from(std::int64_t(0))},
                            true});
    register_method(kWind, {"get_world_to_texture",
                            get_world_to_texture,
                            {"", GDEXTENSION_VARIANT_TYPE_TRANSFORM3D},
                            {cascade},
                            {Variant::from(std::int64_t(0))},
                            true});
    register_method(kWind, {"get_stats", get_stats, {"", GDEXTENSION_VARIANT_TYPE_DICTIONARY}, {}, {}, true});

    register_class({kEmitter, "Node3D", []() -> Instance* { return new Emitter(); }, emitter_notification});
    property(kEmitter, {"kind", GDEXTENSION_VARIANT_TYPE_INT}, set_kind, get_kind, kHintEnum,
             "directional,omni,vortex,cone");
    property(kEmitter, {"strength", GDEXTENSION_VARIANT_TYPE_FLOAT}, set_strength, get_strength);
    property(kEmitter, {"radius", GDEXTENSION_VARIANT_TYPE_FLOAT}, set_radius, get_radius);
}

} // namespace gust::godot4
