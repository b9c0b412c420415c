// A Vulkan 1.2 device and queue: either gust's own instance and device (tests, tools, the sample), with
// validation messages captured so tests can fail on them, or a host engine's device adopted through
// the host's entry points (Jolt-style tiered backends).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <gust/gpu/host_memory.hpp>
#include <gust/gpu/result.hpp>
#include <gust/gpu/vk.hpp>
#include <memory>
#include <memory_resource>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace gust::gpu {

class Profiler;

/// How serious a message from the driver or the validation layer is.
enum class Severity { Info, Warning, Error };

/// Called for every validation or driver message; may be called from any thread.
using MessageCallback = std::function<void(Severity, const std::string&)>;

/// Options for creating a Context.
struct ContextDesc {
    /// Enable VK_LAYER_KHRONOS_validation (creation fails with a clear message if it is not installed).
    bool validation = false;
    /// Device override: a device index ("1") or a case-insensitive substring of its name ("llvmpipe").
    /// Empty means the GUST_DEVICE environment variable, then discrete > integrated > virtual > CPU.
    std::string device;
    /// Receives validation and driver messages; null prints nothing (they are still counted).
    MessageCallback on_message;
    /// Host memory for the Context, the modules created on it and Vulkan's host allocations; null is
    /// new/delete (and the driver's own allocator). Must outlive the Context.
    std::pmr::memory_resource* memory = nullptr;
    /// A file the pipeline cache is read from (when it is whole and holds this device's cache; any other
    /// file, a missing one included, is ignored) and written to by Context::save_pipeline_cache() when it is
    /// missing, empty or a gust cache (any other file is left alone); empty
    /// keeps the cache in memory only. Tools that run once per call (gust voxelize) create their
    /// pipelines from it instead of compiling them.
    std::string pipeline_cache;
    /// When set, the device whose VkPhysicalDeviceIDProperties::deviceUUID equals it (before `device` and
    /// GUST_DEVICE): the physical device of another VkDevice that is to import gust's memory.
    std::optional<std::array<std::uint8_t, VK_UUID_SIZE>> device_uuid;
    /// Enable VK_KHR_external_memory_fd, so images created ImageDesc::exportable can hand their memory to
    /// another VkDevice on the same physical device (creation fails when the device lacks it).
    bool external_memory = false;
    /// The queue must support graphics, which only the raster voxelizer needs. False runs gust on a
    /// compute-only queue family where the device has one (async compute: gust's work overlaps a game's
    /// rendering on its graphics queue), else on a graphics and compute family (pick_queue_family).
    bool needs_graphics = true;
};

/// The queue family gust runs on among `families` (vkGetPhysicalDeviceQueueFamilyProperties' list): with
/// `needs_graphics`, the first with graphics and compute; without, the first with compute but no graphics
/// (an async compute family), else the first with graphics and compute. Families without queues never
/// count. Empty when none fits.
std::optional<std::uint32_t> pick_queue_family(std::span<const VkQueueFamilyProperties> families,
                                               bool needs_graphics);

/// What gust needs from a device, for a host that creates the VkDevice gust adopts. Names are static
/// strings. Context::create() enables the required items and the optional extensions the device has;
/// Context::adopt() checks the physical device supports the required ones.
struct DeviceRequirements {
    /// Lowest VkPhysicalDeviceProperties::apiVersion; the host's instance must ask for it too.
    std::uint32_t api_version = VK_API_VERSION_1_2;
    /// Device extensions the host must enable (empty while everything gust needs is core in 1.2).
    std::vector<const char*> extensions;
    /// Device extensions gust uses only when the host enabled them and lists them in
    /// HostDevice::enabled_extensions (VK_EXT_conservative_rasterization).
    std::vector<const char*> optional_extensions;
    /// Names of the features the host must enable ("geometryShader", "bufferDeviceAddress", ...);
    /// add_required_features() sets them.
    std::vector<const char*> features;
};

/// The device extensions and features gust needs (the same definition Context::create() enables).
DeviceRequirements device_requirements();

/// Sets gust's required features to VK_TRUE in `features` and in the VkPhysicalDeviceVulkan12Features
/// found on its pNext chain, leaving every other flag as it was.
/// Fails, changing nothing, when the chain lacks VkPhysicalDeviceVulkan12Features.
Status add_required_features(VkPhysicalDeviceFeatures2& features);

/// Reports what `physical_device` (of the host's `instance`, queried through `get_instance_proc_addr`)
/// lacks of device_requirements(): API version, extensions and features, each named. Ok when nothing.
Status check_device_support(PFN_vkGetInstanceProcAddr get_instance_proc_addr, VkInstance instance,
                            VkPhysicalDevice physical_device);

/// A host engine's Vulkan objects for Context::adopt(). gust keeps the handles but never destroys them;
/// the host keeps them alive until the Context is destroyed. The host must have created the instance
/// with apiVersion >= 1.2 and the device with device_requirements() enabled (add_required_features()):
/// Vulkan cannot report which features or extensions a device was created with, so gust trusts that.
struct HostDevice {
    VkInstance instance = VK_NULL_HANDLE;              ///< the host's instance (required)
    VkPhysicalDevice physical_device = VK_NULL_HANDLE; ///< the device's physical device (required)
    VkDevice device = VK_NULL_HANDLE;                  ///< the host's device (required)
    /// Family of the queue gust submits to; it must support compute. Without graphics (an async compute
    /// family) the raster voxelizer cannot run there.
    std::uint32_t queue_family = 0;
    /// Index of that queue within its family; the host must have created it (queueCount > queue_index).
    std::uint32_t queue_index = 0;
    /// The host's loader entry point (required); every instance function is loaded through it, and gust
    /// loads no Vulkan library of its own.
    PFN_vkGetInstanceProcAddr get_instance_proc_addr = nullptr;
    /// Loads every device function; null means vkGetDeviceProcAddr from get_instance_proc_addr.
    PFN_vkGetDeviceProcAddr get_device_proc_addr = nullptr;
    /// Device extensions the host enabled; gust uses an optional extension only when it is listed here.
    /// Read during adopt() only.
    std::span<const char* const> enabled_extensions;
    /// Locked around every gust submission to the queue when not null (the host keeps it alive). Vulkan
    /// requires a queue to be externally synchronized, so a host that submits to the same queue from
    /// other threads passes the mutex it holds for its own submissions.
    std::mutex* queue_mutex = nullptr;
    /// Receives validation and driver messages through a messenger gust creates on the host's instance
    /// (which must have VK_EXT_debug_utils enabled); it also sees messages about the host's own calls.
    /// Null creates no messenger.
    MessageCallback on_message;
    /// The host's instance has VK_EXT_debug_utils enabled: gust names its pipelines and buffers and labels
    /// its passes in the host's command buffers (RenderDoc, Nsight). Implied by on_message.
    bool debug_utils = false;
    /// As ContextDesc::memory.
    std::pmr::memory_resource* memory = nullptr;
};

/// What was chosen, for stats and `gust info`.
struct DeviceInfo {
    std::pmr::string name; ///< VkPhysicalDeviceProperties::deviceName
    std::string type;      ///< "discrete", "integrated", "virtual", "cpu" or "other" (no heap: short)
    std::uint32_t api_version = 0;
    std::uint32_t vendor_id = 0;
    std::pmr::string driver;                 ///< driver name and info
    bool conservative_rasterization = false; ///< VK_EXT_conservative_rasterization enabled
    /// gust's queue family supports graphics, so the raster voxelizer can run; false on an async compute
    /// family (compute without graphics).
    bool graphics_queue = false;
    float timestamp_period_ns = 0.0f; ///< 0 when the queue has no timestamps
    std::uint64_t max_storage_buffer_range = 0;
    std::uint64_t max_allocation_size = 0;
    std::uint32_t subgroup_size = 0;
    /// Largest one-dimensional compute workgroup: min(maxComputeWorkGroupInvocations,
    /// maxComputeWorkGroupSize[0]); Vulkan guarantees 128.
    std::uint32_t max_workgroup_size = 0;
};

/// GPU work counted over a Context's life; a frame's cost is the difference across it.
struct WorkCounts {
    std::uint64_t dispatches = 0;  ///< dispatches and draws recorded, indirect ones included
    std::uint64_t submissions = 0; ///< queue submissions
    std::uint64_t waits = 0;       ///< times the host waited for the GPU
    /// Dependent stages: dispatches and draws recorded after an execution barrier, or first in a command
    /// buffer gust began. Each waits for the GPU work before it to drain, so on a GPU a frame of small
    /// grids costs about its stages times the drain and launch latency, whatever its dispatches.
    std::uint64_t stages = 0;
};

/// One device and one queue that supports compute, and graphics unless it is an async compute queue
/// (DeviceInfo::graphics_queue). Not copyable; thread-compatible
/// (one thread records and submits at a time). With an adopted device, gust submits to the host's
/// queue, which Vulkan requires to be externally synchronized: the host must not submit to that queue
/// from another thread while a gust call runs, unless it passes HostDevice::queue_mutex.
class Context : public HostObject {
  public:
    /// Creates an instance and picks a device per `desc`. Fails with a message naming what is missing.
    static Result<std::unique_ptr<Context>> create(const ContextDesc& desc);
    /// Uses the host's device and queue; creates only its own command pool, fence and (with
    /// `host.on_message`) debug messenger, and destroys only those. Fails with a message naming the bad
    /// field or what the physical device lacks.
    static Result<std::unique_ptr<Context>> adopt(const HostDevice& host);
    /// Waits for the device and destroys it and the instance when gust created them; an adopted device
    /// is left alone (gust's own submissions are already complete when submit_and_wait returns).
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    /// The dispatch table every call goes through.
    const Dispatch& vk() const { return vk_; }
    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physical_device() const { return physical_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    std::uint32_t queue_family() const { return queue_family_; }
    /// False for an adopted device: the instance and device belong to the host.
    bool owns_device() const { return owns_device_; }
    const DeviceInfo& info() const { return info_; }
    /// Host memory of this Context and everything created on it (ContextDesc::memory).
    std::pmr::memory_resource* memory() const { return host_memory_; }
    /// What every vkCreate*, vkAllocate* and matching destroy call passes as pAllocator.
    const VkAllocationCallbacks* allocator() const { return allocator_.callbacks(); }
    /// Names and types of every device the instance sees, in enumeration order (for errors and `gust info`);
    /// empty for an adopted device.
    const std::pmr::vector<std::pmr::string>& device_names() const { return device_names_; }

    /// Dispatches, draws, stages, submissions and waits so far (Pipeline counts dispatches and draws, the
    /// barriers of buffer.hpp and Image mark where a stage ends, submit_and_wait counts the others).
    const WorkCounts& work() const { return work_; }
    /// Internal: a dispatch or draw was recorded; the first after a barrier starts a stage.
    void count_dispatch() const {
        ++work_.dispatches;
        if (barrier_recorded_) ++work_.stages;
        barrier_recorded_ = false;
    }
    /// Times every dispatch and draw recorded from now on apart in `profiler`, under its pipeline's name
    /// (null: stops). The caller resets the profiler in the recording first. Each time runs from the end of
    /// all the work recorded before the dispatch to the end of the dispatch, so work that overlaps counts
    /// once and the times add up to the whole (System::set_dispatch_timing).
    void time_dispatches(Profiler* profiler) { dispatch_profiler_ = profiler; }
    /// The profiler of time_dispatches, or null.
    Profiler* dispatch_profiler() const { return dispatch_profiler_; }
    /// Internal: an execution barrier was recorded (or a command buffer begun): the next dispatch waits.
    void count_barrier() const { barrier_recorded_ = true; }

    /// Waits until nothing runs on gust's resources: the whole device when gust owns it, else the queue it
    /// was given (HostDevice::queue_mutex held), where the host submits what gust recorded for it.
    void wait_idle() const;
    /// A render pass of one subpass without attachments, which every graphics pipeline is made for (Vulkan
    /// 1.0's, not dynamic rendering: a host's device need not enable it), and a framebuffer for it
    /// kMaxFramebufferExtent texels square, inside which a pass sets its render area.
    VkRenderPass attachmentless_pass() const { return render_pass_; }
    VkFramebuffer attachmentless_framebuffer() const { return framebuffer_; }
    /// Width and height of attachmentless_framebuffer(): Vulkan's guaranteed maxFramebufferWidth and Height.
    static constexpr std::uint32_t kMaxFramebufferExtent = 4096;
    /// The pipeline cache every pipeline is created through (ContextDesc::pipeline_cache).
    VkPipelineCache pipeline_cache() const { return pipeline_cache_; }
    /// Writes the pipeline cache to ContextDesc::pipeline_cache (nothing when none was named), so the
    /// next process creates its pipelines from it instead of compiling them. Creates the file's folder;
    /// replaces the file whole (written under another name, then renamed), never in part.
    Status save_pipeline_cache() const;
    /// Whether ContextDesc::pipeline_cache named a file that held this device's cache, given to Vulkan.
    bool pipeline_cache_loaded() const { return pipeline_cache_loaded_; }

    /// Whether VK_KHR_external_memory_fd is on (ContextDesc::external_memory): exportable images work.
    bool external_memory() const { return vk_.vkGetMemoryFdKHR != nullptr; }

    /// Whether VK_EXT_debug_utils is on, so that names and labels reach capture tools.
    bool debug_utils() const { return vk_.vkSetDebugUtilsObjectNameEXT != nullptr; }
    /// Names a Vulkan object of this device for capture tools (RenderDoc, Nsight): `handle` is the object
    /// cast to std::uint64_t (`std::uint64_t(sampler)`), `type` its VK_OBJECT_TYPE_*. Nothing without
    /// VK_EXT_debug_utils; `name` may be null (then nothing either). Buffer::create, Image::create and the
    /// Pipeline factories name their objects through it; call it for any other object gust creates.
    void name(VkObjectType type, std::uint64_t handle, const char* name) const;
    /// Opens a labelled region of `cmd` (a pass) for capture tools; close it with end_label().
    void begin_label(VkCommandBuffer cmd, const char* name) const;
    void end_label(VkCommandBuffer cmd) const;

    /// Validation-layer messages of warning or error severity seen so far (tests fail when > 0).
    std::uint32_t validation_messages() const { return validation_messages_.load(); }
    /// The most recent such message (empty if none).
    std::string last_validation_message() const;

    /// Records commands with `record` into a one-time command buffer, submits and waits (holding
    /// HostDevice::queue_mutex, if given, while submitting). On an adopted device the commands start with
    /// a full barrier, so they run after whatever the host submitted to the queue before.
    template <class Record> Status submit_and_wait(Record&& record) {
        VkCommandBuffer cmd = VK_NULL_HANDLE;
        if (Status s = begin_one_time(cmd); !s) return s;
        try {
            record(cmd);
        } catch (...) {
            abandon_one_time(cmd); // a recording cut short (host memory ran out) is freed, never submitted
            throw;
        }
        return end_one_time(cmd);
    }

    /// Frames in flight (work recorded into the host's command buffers, which run later): from the first
    /// call on, buffers released are kept until retire() says the frames that may use them completed,
    /// and each Profiler writes the frame's timestamps into a slot of its own (Profiler::read_frame).
    /// `frame` numbers the frame being recorded; buffers released from now on are tagged with it.
    void begin_frame(std::uint64_t frame);
    /// Destroys the buffers released while recording frames up to `completed` (which have completed).
    void retire(std::uint64_t completed);
    /// True once begin_frame() was called: recorded work may still be pending when a call returns.
    bool deferred() const { return deferred_; }
    /// The frame begin_frame() last named (0 before the first call).
    std::uint64_t recording_frame() const { return recording_frame_; }
    /// Internal: called by Buffer when it is released while deferred(). Never allocates: every live
    /// Buffer holds a slot of the list reserved when it was created (reserve_release_slot).
    void release_later(VkBuffer buffer, VkDeviceMemory memory) noexcept;
    /// Internal: Buffer::create keeps room in the release list for one more buffer (it fails, rather than a
    /// later release, when host memory runs out); drop_release_slot gives it back once the buffer is freed.
    Status reserve_release_slot() noexcept;
    void drop_release_slot() noexcept;

    /// Index of a memory type allowed by `type_bits` having all of `required` (and as many of
    /// `preferred` as possible); UINT32_MAX if none.
    std::uint32_t find_memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags required,
                                   VkMemoryPropertyFlags preferred) const;
    /// Property flags of a memory type index.
    VkMemoryPropertyFlags memory_flags(std::uint32_t type_index) const;

    /// Internal: called by the debug messenger.
    void report(Severity severity, bool validation, const std::string& message);

  private:
    explicit Context(std::pmr::memory_resource* memory);
    /// submit_and_wait(): a one-time command buffer begun (after the adopted device's barrier), then
    /// ended, submitted, waited for and freed.
    Status begin_one_time(VkCommandBuffer& cmd);
    Status end_one_time(VkCommandBuffer cmd);
    void abandon_one_time(VkCommandBuffer cmd);
    Status init(const ContextDesc& desc);
    Status init_adopted(const HostDevice& host);
    Status pick_device(std::string_view override_spec,
                       const std::optional<std::array<std::uint8_t, VK_UUID_SIZE>>& uuid);
    Status create_device(bool external_memory, bool needs_graphics);
    Status finish_device(std::uint32_t queue_index);
    /// The pipeline cache, from ContextDesc::pipeline_cache when that file holds the cache of the device
    /// `props` describes.
    Status create_pipeline_cache(const VkPhysicalDeviceProperties& props);

    std::pmr::memory_resource* host_memory_;
    VulkanAllocator allocator_;
    Dispatch vk_;
    void* loader_ = nullptr;
    /// Load addresses of the shared objects in the process before init() opened the loader: those loaded
    /// since (the loader's drivers and layers) are kept loaded when the instance goes (keep_drivers_loaded).
    std::pmr::vector<std::uintptr_t> objects_before_;
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    std::uint32_t queue_family_ = 0;
    bool owns_device_ = true;
    std::mutex* queue_mutex_ = nullptr;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    VkRenderPass render_pass_ = VK_NULL_HANDLE;
    VkFramebuffer framebuffer_ = VK_NULL_HANDLE;
    VkPipelineCache pipeline_cache_ = VK_NULL_HANDLE;
    std::pmr::string pipeline_cache_path_;
    bool pipeline_cache_loaded_ = false;
    VkPhysicalDeviceMemoryProperties memory_{};
    DeviceInfo info_;
    std::pmr::vector<std::pmr::string> device_names_;
    MessageCallback on_message_;
    struct Released {
        std::uint64_t frame;
        VkBuffer buffer;
        VkDeviceMemory memory;
    };
    bool deferred_ = false;
    std::uint64_t recording_frame_ = 0;
    std::size_t live_buffers_ = 0; ///< Buffers holding a release slot
    std::pmr::vector<Released> released_;
    // Counters of what was recorded, not state: the const recording helpers (buffer.hpp) count too.
    mutable WorkCounts work_;
    mutable bool barrier_recorded_ = true;
    Profiler* dispatch_profiler_ = nullptr;
    std::atomic<std::uint32_t> validation_messages_{0};
    mutable std::mutex message_mutex_;
    std::pmr::string last_message_;
};

} // namespace gust::gpu
