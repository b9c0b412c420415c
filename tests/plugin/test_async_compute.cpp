// Async compute (issue 41): gust on a compute queue beside the host's graphics queue, its frame recorded into
// the host's compute submission between the host's own semaphores (docs/api.md "Async compute").
#include "host_vulkan.hpp"
#include "system_test_support.hpp"

#include <cmath>
#include <glm/gtc/packing.hpp>
#include <gust/voxelizer/voxelizer.hpp>
#include <iterator>
#include <vector>

namespace gust::test {
namespace {

constexpr int kFrames = 4;
constexpr std::uint32_t kInFlight = 2;
constexpr float kDt = 0.05f;
// Cell centres of the 16x8x16 domain of 1 m cells from (-8, 0, -8): before, beside, behind and above the
// boxes.
constexpr std::uint32_t kCells[][3] = {{2, 2, 8}, {6, 2, 9}, {11, 3, 8}, {8, 6, 4}};
constexpr std::size_t kPoints = std::size(kCells);

Vec3 centre(const std::uint32_t (&cell)[3]) {
    return {-8.0f + float(cell[0]) + 0.5f, float(cell[1]) + 0.5f, -8.0f + float(cell[2]) + 0.5f};
}

/// A static box and a moving one in a wind of 3 m/s; `step` advances frame f.
template <class Step> void run_scene(System& system, Step&& step) {
    Box box(1.0f);
    MeshId mesh = 0;
    InstanceId fixed = 0, moving = 0;
    ASSERT_TRUE(system.create_mesh(box.desc(), mesh));
    ASSERT_TRUE(system.create_instance(mesh, translation(-3.0f, 2.0f, 0.0f), false, fixed));
    ASSERT_TRUE(system.create_instance(mesh, translation(3.0f, 2.0f, 0.0f), true, moving));
    ASSERT_TRUE(system.set_ambient({3.0f, 0.0f, 0.0f}));
    for (int f = 0; f < kFrames; ++f) {
        ASSERT_TRUE(system.set_transform(moving, translation(3.0f, 2.0f, 0.5f * float(f))));
        step();
    }
}

/// The host's side of an async compute frame: its own command pools on its graphics family and on gust's
/// (compute) family, per frame in flight three command buffers (its work before gust's, gust's, its work
/// after), three binary semaphores and a fence, and a host-visible buffer its last submission copies the
/// wind texture into. Where the device has no compute-only family both are one family and one queue.
class AsyncHost {
  public:
    explicit AsyncHost(HostVulkan& host) : host_(host), device_(host.device().device) {
        load(get_queue_, "vkGetDeviceQueue");
        load(create_pool_, "vkCreateCommandPool");
        load(destroy_pool_, "vkDestroyCommandPool");
        load(allocate_, "vkAllocateCommandBuffers");
        load(begin_, "vkBeginCommandBuffer");
        load(end_, "vkEndCommandBuffer");
        load(create_semaphore_, "vkCreateSemaphore");
        load(destroy_semaphore_, "vkDestroySemaphore");
        load(create_fence_, "vkCreateFence");
        load(destroy_fence_, "vkDestroyFence");
        load(wait_fences_, "vkWaitForFences");
        load(reset_fences_, "vkResetFences");
        load(submit_, "vkQueueSubmit");
        load(barrier_, "vkCmdPipelineBarrier");
        load(fill_, "vkCmdFillBuffer");
        load(copy_, "vkCmdCopyImageToBuffer");
        load(create_buffer_, "vkCreateBuffer");
        load(destroy_buffer_, "vkDestroyBuffer");
        load(requirements_, "vkGetBufferMemoryRequirements");
        load(allocate_memory_, "vkAllocateMemory");
        load(free_memory_, "vkFreeMemory");
        load(bind_, "vkBindBufferMemory");
        load(map_, "vkMapMemory");
    }
    ~AsyncHost() {
        for (VkFence f : fences_)
            destroy_fence_(device_, f, nullptr);
        for (VkSemaphore s : semaphores_)
            destroy_semaphore_(device_, s, nullptr);
        for (VkCommandPool pool : pools_)
            if (pool) destroy_pool_(device_, pool, nullptr);
        if (buffer_) destroy_buffer_(device_, buffer_, nullptr);
        if (memory_) free_memory_(device_, memory_, nullptr);
    }

    /// Creates everything for the host's `graphics` family and gust's `compute` family (its
    /// HostDevice::queue_family; queue 0 of each), and a readback of `bytes` for each frame in flight.
    void create(std::uint32_t graphics, std::uint32_t compute, VkDeviceSize bytes) {
        families_[0] = graphics;
        families_[1] = compute;
        bytes_ = bytes;
        for (int q = 0; q < 2; ++q) {
            get_queue_(device_, families_[q], 0, &queues_[q]);
            VkCommandPoolCreateInfo pool{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
            pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
            pool.queueFamilyIndex = families_[q];
            ASSERT_EQ(create_pool_(device_, &pool, nullptr, &pools_[q]), VK_SUCCESS);
            VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
            alloc.commandPool = pools_[q];
            alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
            alloc.commandBufferCount = q == 0 ? 2 * kInFlight : kInFlight;
            ASSERT_EQ(allocate_(device_, &alloc, q == 0 ? graphics_commands_ : compute_commands_),
                      VK_SUCCESS);
        }
        const VkSemaphoreCreateInfo semaphore{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        for (VkSemaphore& s : semaphores_)
            ASSERT_EQ(create_semaphore_(device_, &semaphore, nullptr, &s), VK_SUCCESS);
        VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        fence.flags = VK_FENCE_CREATE_SIGNALED_BIT;
        for (VkFence& f : fences_)
            ASSERT_EQ(create_fence_(device_, &fence, nullptr, &f), VK_SUCCESS);

        VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        info.size = kInFlight * bytes + 256;
        info.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
        ASSERT_EQ(create_buffer_(device_, &info, nullptr, &buffer_), VK_SUCCESS);
        VkMemoryRequirements req;
        requirements_(device_, buffer_, &req);
        VkPhysicalDeviceMemoryProperties props;
        reinterpret_cast<PFN_vkGetPhysicalDeviceMemoryProperties>(host_.device().get_instance_proc_addr(
            host_.device().instance, "vkGetPhysicalDeviceMemoryProperties"))(host_.device().physical_device,
                                                                             &props);
        const VkMemoryPropertyFlags visible =
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        VkMemoryAllocateInfo memory{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        memory.allocationSize = req.size;
        memory.memoryTypeIndex = props.memoryTypeCount;
        for (std::uint32_t t = props.memoryTypeCount; t-- > 0;)
            if ((req.memoryTypeBits >> t & 1u) && (props.memoryTypes[t].propertyFlags & visible) == visible)
                memory.memoryTypeIndex = t;
        ASSERT_LT(memory.memoryTypeIndex, props.memoryTypeCount);
        ASSERT_EQ(allocate_memory_(device_, &memory, nullptr, &memory_), VK_SUCCESS);
        ASSERT_EQ(bind_(device_, buffer_, memory_, 0), VK_SUCCESS);
        ASSERT_EQ(map_(device_, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), VK_SUCCESS);
    }

    /// One frame: the host's work on its graphics queue signals `gust_may_start`; gust's frame (recorded by
    /// `record` into the compute command buffer, followed by the wind texture's release to the graphics
    /// family) waits for it and for the last frame's read of the texture, and signals `wind_written`; the
    /// host's last submission, on its graphics queue, waits for that, acquires the texture, copies it out and
    /// signals `texture_read`.
    template <class Record> void frame(std::uint64_t f, Record&& record) {
        const std::size_t slot = f % kInFlight, last = (f + kInFlight - 1) % kInFlight;
        // The frame contract's completion: frame f - kInFlight completed before frame f is recorded.
        ASSERT_EQ(wait_fences_(device_, 1, &fences_[slot], VK_TRUE, UINT64_MAX), VK_SUCCESS);
        ASSERT_EQ(reset_fences_(device_, 1, &fences_[slot]), VK_SUCCESS);
        VkCommandBuffer before = graphics_commands_[2 * slot], compute = compute_commands_[slot],
                        after = graphics_commands_[2 * slot + 1];
        VkSemaphore gust_may_start = semaphores_[3 * slot], wind_written = semaphores_[3 * slot + 1],
                    texture_read = semaphores_[3 * slot + 2];
        const std::uint32_t graphics_family = families_[0], compute_family = families_[1];
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;

        ASSERT_EQ(begin_(before, &begin), VK_SUCCESS);
        fill_(before, buffer_, kInFlight * bytes_, 256, std::uint32_t(f));
        ASSERT_EQ(end_(before), VK_SUCCESS);
        VkSubmitInfo first{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        first.commandBufferCount = 1;
        first.pCommandBuffers = &before;
        first.signalSemaphoreCount = 1;
        first.pSignalSemaphores = &gust_may_start;
        ASSERT_EQ(submit_(queues_[0], 1, &first, VK_NULL_HANDLE), VK_SUCCESS);

        ASSERT_EQ(begin_(compute, &begin), VK_SUCCESS);
        record(compute);
        texture_barrier(compute, compute_family, graphics_family, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                        VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_ACCESS_TRANSFER_WRITE_BIT, 0,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
        ASSERT_EQ(end_(compute), VK_SUCCESS);
        // gust's first barrier orders it after earlier work on its own queue only: the last frame's read of
        // the texture, on the graphics queue, is waited for here.
        const VkSemaphore waits[] = {gust_may_start, semaphores_[3 * last + 2]};
        const VkPipelineStageFlags all[] = {VK_PIPELINE_STAGE_ALL_COMMANDS_BIT,
                                            VK_PIPELINE_STAGE_ALL_COMMANDS_BIT};
        VkSubmitInfo second{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        second.waitSemaphoreCount = f == 0 ? 1 : 2;
        second.pWaitSemaphores = waits;
        second.pWaitDstStageMask = all;
        second.commandBufferCount = 1;
        second.pCommandBuffers = &compute;
        second.signalSemaphoreCount = 1;
        second.pSignalSemaphores = &wind_written;
        ASSERT_EQ(submit_(queues_[1], 1, &second, VK_NULL_HANDLE), VK_SUCCESS);

        ASSERT_EQ(begin_(after, &begin), VK_SUCCESS);
        texture_barrier(after, compute_family, graphics_family, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                        VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, 0, VK_ACCESS_TRANSFER_READ_BIT,
                        VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
        texture_barrier(after, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                        VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, 0,
                        VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT);
        VkBufferImageCopy region{};
        region.bufferOffset = slot * bytes_;
        region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        region.imageExtent = {texture_.extent[0], texture_.extent[1], texture_.extent[2]};
        copy_(after, texture_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer_, 1, &region);
        texture_barrier(after, VK_QUEUE_FAMILY_IGNORED, VK_QUEUE_FAMILY_IGNORED,
                        VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                        VK_ACCESS_TRANSFER_READ_BIT, VK_ACCESS_SHADER_READ_BIT,
                        VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT);
        ASSERT_EQ(end_(after), VK_SUCCESS);
        const VkPipelineStageFlags copy_stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
        VkSubmitInfo third{VK_STRUCTURE_TYPE_SUBMIT_INFO};
        third.waitSemaphoreCount = 1;
        third.pWaitSemaphores = &wind_written;
        third.pWaitDstStageMask = &copy_stage;
        third.commandBufferCount = 1;
        third.pCommandBuffers = &after;
        third.signalSemaphoreCount = 1;
        third.pSignalSemaphores = &texture_read;
        ASSERT_EQ(submit_(queues_[0], 1, &third, fences_[slot]), VK_SUCCESS);
    }

    void finish() { ASSERT_EQ(wait_fences_(device_, kInFlight, fences_, VK_TRUE, UINT64_MAX), VK_SUCCESS); }
    void set_texture(const WindTexture& texture) { texture_ = texture; }
    /// The wind texture's rgba16f texels as frame f's last submission copied them.
    const std::uint16_t* texels(std::uint64_t f) const {
        return reinterpret_cast<const std::uint16_t*>(static_cast<const char*>(mapped_) +
                                                      (f % kInFlight) * bytes_);
    }

  private:
    template <class Fn> void load(Fn& fn, const char* name) {
        fn = reinterpret_cast<Fn>(host_.device_function(name));
        ASSERT_NE(fn, nullptr) << name;
    }
    void texture_barrier(VkCommandBuffer cmd, std::uint32_t src_family, std::uint32_t dst_family,
                         VkImageLayout from, VkImageLayout to, VkAccessFlags src_access,
                         VkAccessFlags dst_access, VkPipelineStageFlags src_stage,
                         VkPipelineStageFlags dst_stage) {
        VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
        b.srcAccessMask = src_access;
        b.dstAccessMask = dst_access;
        b.oldLayout = from;
        b.newLayout = to;
        b.srcQueueFamilyIndex = src_family;
        b.dstQueueFamilyIndex = dst_family;
        b.image = texture_.image;
        b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        barrier_(cmd, src_stage, dst_stage, 0, 0, nullptr, 0, nullptr, 1, &b);
    }

    HostVulkan& host_;
    VkDevice device_;
    std::uint32_t families_[2] = {}; ///< graphics, compute
    VkDeviceSize bytes_ = 0;
    VkQueue queues_[2] = {};
    VkCommandPool pools_[2] = {};
    VkCommandBuffer graphics_commands_[2 * kInFlight] = {};
    VkCommandBuffer compute_commands_[kInFlight] = {};
    VkSemaphore semaphores_[3 * kInFlight] = {};
    VkFence fences_[kInFlight] = {};
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    void* mapped_ = nullptr;
    WindTexture texture_;
    PFN_vkGetDeviceQueue get_queue_ = nullptr;
    PFN_vkCreateCommandPool create_pool_ = nullptr;
    PFN_vkDestroyCommandPool destroy_pool_ = nullptr;
    PFN_vkAllocateCommandBuffers allocate_ = nullptr;
    PFN_vkBeginCommandBuffer begin_ = nullptr;
    PFN_vkEndCommandBuffer end_ = nullptr;
    PFN_vkCreateSemaphore create_semaphore_ = nullptr;
    PFN_vkDestroySemaphore destroy_semaphore_ = nullptr;
    PFN_vkCreateFence create_fence_ = nullptr;
    PFN_vkDestroyFence destroy_fence_ = nullptr;
    PFN_vkWaitForFences wait_fences_ = nullptr;
    PFN_vkResetFences reset_fences_ = nullptr;
    PFN_vkQueueSubmit submit_ = nullptr;
    PFN_vkCmdPipelineBarrier barrier_ = nullptr;
    PFN_vkCmdFillBuffer fill_ = nullptr;
    PFN_vkCmdCopyImageToBuffer copy_ = nullptr;
    PFN_vkCreateBuffer create_buffer_ = nullptr;
    PFN_vkDestroyBuffer destroy_buffer_ = nullptr;
    PFN_vkGetBufferMemoryRequirements requirements_ = nullptr;
    PFN_vkAllocateMemory allocate_memory_ = nullptr;
    PFN_vkFreeMemory free_memory_ = nullptr;
    PFN_vkBindBufferMemory bind_ = nullptr;
    PFN_vkMapMemory map_ = nullptr;
};

// The host submits its own work signalling a semaphore, then the command buffer gust's step recorded into
// (waiting on that semaphore, signalling another) on its async compute queue, then work that waits on the
// second and copies the wind texture out, two frames in flight. On a device with a compute-only family the
// texture changes family each frame (release, acquire); lavapipe has one family and one queue for both. The
// wind is OwnQueue's for the same scene and steps, exactly (the solve is deterministic: fixed-point atomics,
// reductions in a fixed order), and the layer reports nothing.
TEST(AsyncCompute, aFrameBetweenTheHostsSemaphoresGivesTheWindOfAnOwnQueueStep) {
    Vec3 points[kPoints];
    for (std::size_t i = 0; i < kPoints; ++i)
        points[i] = centre(kCells[i]);
    Vec3 own[kPoints], recorded[kPoints];
    {
        Watch watch;
        SystemDesc desc = small_desc(watch);
        desc.voxelize = VoxelizePath::Compute;
        std::unique_ptr<System> system;
        const Outcome created = System::create(desc, system);
        ASSERT_TRUE(created) << created.message();
        run_scene(*system, [&] { ASSERT_TRUE(system->step(kDt)); });
        ASSERT_TRUE(system->query(points, own));
        system.reset();
        EXPECT_EQ(watch.errors, 0) << watch.last;
    }

    HostVulkan host(false, true);
    ASSERT_TRUE(host.ok()) << host.error();
    HostDevice compute_queue = host.device();
    compute_queue.queue_family = host.compute_family();
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.voxelize = VoxelizePath::Compute;
    desc.host = &compute_queue;
    desc.submission = Submission::HostCommands;
    desc.frames_in_flight = kInFlight;
    std::unique_ptr<System> system;
    const Outcome created = System::create(desc, system);
    ASSERT_TRUE(created) << created.message();

    // What the System reports of its queue, against the family's own flags.
    const QueueInfo queue = system->queue_info();
    EXPECT_EQ(queue.family, host.compute_family());
    std::uint32_t count = 0;
    const auto families =
        reinterpret_cast<PFN_vkGetPhysicalDeviceQueueFamilyProperties>(host.device().get_instance_proc_addr(
            host.device().instance, "vkGetPhysicalDeviceQueueFamilyProperties"));
    families(host.device().physical_device, &count, nullptr);
    std::vector<VkQueueFamilyProperties> props(count);
    families(host.device().physical_device, &count, props.data());
    ASSERT_LT(queue.family, count);
    EXPECT_EQ(queue.async_compute, (props[queue.family].queueFlags & VK_QUEUE_GRAPHICS_BIT) == 0);

    AsyncHost async(host);
    const WindTexture& texture = system->wind_texture();
    const VkDeviceSize texel_bytes =
        VkDeviceSize(texture.extent[0]) * texture.extent[1] * texture.extent[2] * 8;
    async.create(host.device().queue_family, queue.family, texel_bytes);
    async.set_texture(texture);
    std::uint64_t f = 0;
    run_scene(*system, [&] {
        async.frame(f++, [&](VkCommandBuffer cmd) {
            const Outcome stepped = system->step(kDt, cmd);
            ASSERT_TRUE(stepped) << stepped.message();
        });
    });
    async.finish();
    ASSERT_EQ(f, std::uint64_t(kFrames));
    ASSERT_TRUE(system->query(points, recorded));
    for (std::size_t i = 0; i < kPoints; ++i) {
        EXPECT_EQ(recorded[i].x, own[i].x) << "point " << i;
        EXPECT_EQ(recorded[i].y, own[i].y) << "point " << i;
        EXPECT_EQ(recorded[i].z, own[i].z) << "point " << i;
        // The last frame's texels as the host's last submission copied them: the wind at the cell's centre,
        // in half floats.
        const std::uint32_t* c = kCells[i];
        const std::uint16_t* texel =
            async.texels(kFrames - 1) + 4 * ((c[2] * texture.extent[1] + c[1]) * texture.extent[0] + c[0]);
        EXPECT_NEAR(glm::unpackHalf1x16(texel[0]), own[i].x, 2e-3f * (1.0f + std::abs(own[i].x))) << i;
        EXPECT_NEAR(glm::unpackHalf1x16(texel[1]), own[i].y, 2e-3f * (1.0f + std::abs(own[i].y))) << i;
        EXPECT_NEAR(glm::unpackHalf1x16(texel[2]), own[i].z, 2e-3f * (1.0f + std::abs(own[i].z))) << i;
    }
    EXPECT_GT(own[0].x, 1.0f) << "the ambient wind reaches the first point";
    system.reset();
    EXPECT_EQ(watch.errors, 0) << watch.last;
    EXPECT_EQ(host.messages(), 0);
}

// Only the raster voxelizer needs graphics: on an async compute queue it is refused, naming the queue and the
// paths that run there; compute and auto run anywhere.
TEST(AsyncCompute, theRasterPathIsRefusedOnAQueueWithoutGraphics) {
    gpu::DeviceInfo compute_only;
    compute_only.name = "Some GPU";
    compute_only.graphics_queue = false;
    const Status refused = check_method(VoxelizeMethod::Raster, compute_only);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.message().find("compute-only (async compute) queue of 'Some GPU'"), std::string::npos)
        << refused.message();
    EXPECT_NE(refused.message().find("compute or auto path"), std::string::npos) << refused.message();
    EXPECT_TRUE(check_method(VoxelizeMethod::Compute, compute_only));
    EXPECT_TRUE(check_method(VoxelizeMethod::Auto, compute_only));
    gpu::DeviceInfo graphics;
    graphics.graphics_queue = true;
    EXPECT_TRUE(check_method(VoxelizeMethod::Raster, graphics));

    // A System asked for the raster path takes a queue with graphics on its own device.
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.voxelize = VoxelizePath::Raster;
    std::unique_ptr<System> system;
    const Outcome created = System::create(desc, system);
    ASSERT_TRUE(created) << created.message();
    EXPECT_FALSE(system->queue_info().async_compute);
}

} // namespace
} // namespace gust::test
