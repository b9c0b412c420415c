// A Vulkan 1.3 instance, device and queue for gust's own use (tests, tools, the sample), with
// validation messages captured so tests can fail on them.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <gust/gpu/result.hpp>
#include <gust/gpu/vk.hpp>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace gust::gpu {

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
};

/// What was chosen, for stats and `gust info`.
struct DeviceInfo {
    std::string name; ///< VkPhysicalDeviceProperties::deviceName
    std::string type; ///< "discrete", "integrated", "virtual", "cpu" or "other"
    std::uint32_t api_version = 0;
    std::uint32_t vendor_id = 0;
    std::string driver;                      ///< driver name and info
    bool conservative_rasterization = false; ///< VK_EXT_conservative_rasterization enabled
    float timestamp_period_ns = 0.0f;        ///< 0 when the queue has no timestamps
    std::uint64_t max_storage_buffer_range = 0;
    std::uint64_t max_allocation_size = 0;
    std::uint32_t subgroup_size = 0;
};

/// One device and one queue that supports graphics and compute. Not copyable; thread-compatible
/// (one thread records and submits at a time).
class Context {
  public:
    /// Creates an instance and picks a device per `desc`. Fails with a message naming what is missing.
    static Result<std::unique_ptr<Context>> create(const ContextDesc& desc);
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
    const DeviceInfo& info() const { return info_; }
    /// Names and types of every device the instance sees, in enumeration order (for errors and `gust info`).
    const std::vector<std::string>& device_names() const { return device_names_; }

    /// Validation-layer messages of warning or error severity seen so far (tests fail when > 0).
    std::uint32_t validation_messages() const { return validation_messages_.load(); }
    /// The most recent such message (empty if none).
    std::string last_validation_message() const;

    /// Records commands with `record` into a one-time command buffer, submits and waits.
    Status submit_and_wait(const std::function<void(VkCommandBuffer)>& record);

    /// Index of a memory type allowed by `type_bits` having all of `required` (and as many of
    /// `preferred` as possible); UINT32_MAX if none.
    std::uint32_t find_memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags required,
                                   VkMemoryPropertyFlags preferred) const;
    /// Property flags of a memory type index.
    VkMemoryPropertyFlags memory_flags(std::uint32_t type_index) const;

    /// Internal: called by the debug messenger.
    void report(Severity severity, bool validation, const std::string& message);

  private:
    Context() = default;
    Status init(const ContextDesc& desc);
    Status pick_device(const std::string& override_spec);
    Status create_device();

    Dispatch vk_;
    void* loader_ = nullptr;
    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    std::uint32_t queue_family_ = 0;
    VkCommandPool pool_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    VkPhysicalDeviceMemoryProperties memory_{};
    DeviceInfo info_;
    std::vector<std::string> device_names_;
    MessageCallback on_message_;
    std::atomic<std::uint32_t> validation_messages_{0};
    mutable std::mutex message_mutex_;
    std::string last_message_;
};

} // namespace gust::gpu
