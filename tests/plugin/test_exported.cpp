// SystemDesc::exported_copies: gust on a device of its own exports copies of its wind textures, and another
// VkDevice on the same physical device (a host engine's, HostVulkan) imports one and reads the wind gust
// computed, with no copy through the CPU and no submission of gust's on the host's queue (docs/api.md
// "Sharing the wind image with another device").
#include "host_vulkan.hpp"
#include "system_test_support.hpp"

#include <cmath>
#include <cstring>
#include <gtest/gtest.h>
#include <gust/gust.hpp>
#include <unistd.h>
#include <vector>

namespace gust::test {
namespace {

/// IEEE half to float, the subnormals included.
float from_half(std::uint16_t h) {
    const int exponent = (h >> 10) & 0x1f, mantissa = h & 0x3ff;
    const float sign = (h & 0x8000) ? -1.0f : 1.0f;
    if (exponent == 0) return sign * std::ldexp(float(mantissa), -24);
    return sign * std::ldexp(float(mantissa | 0x400), exponent - 25);
}

/// The host's side: the device functions it calls to import gust's copy and read it back.
template <class Fn> Fn fn(const HostVulkan& host, const char* name) {
    return reinterpret_cast<Fn>(host.device_function(name));
}

TEST(ExportedCopies, RefusesBadUse) {
    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.exported_copies = 9;
    std::unique_ptr<System> system;
    EXPECT_EQ(System::create(desc, system).code(), ErrorCode::InvalidArgument);
    desc.exported_copies = 0;
    ASSERT_TRUE(System::create(desc, system));
    ExportedImage e;
    EXPECT_EQ(system->export_wind_copy(0, 0, e).code(), ErrorCode::NotEnabled);
    EXPECT_EQ(system->copy_wind_textures(0).code(), ErrorCode::NotEnabled);
    system.reset();
    desc.exported_copies = 2;
    ASSERT_TRUE(System::create(desc, system));
    EXPECT_EQ(system->export_wind_copy(1, 0, e).code(), ErrorCode::InvalidArgument); // one cascade
    EXPECT_EQ(system->export_wind_copy(0, 2, e).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(system->copy_wind_textures(2).code(), ErrorCode::InvalidArgument);
    EXPECT_EQ(watch.errors, 0) << watch.last;
}

TEST(ExportedCopies, anotherDeviceReadsTheWindGustComputed) {
    HostVulkan host(true);
    ASSERT_TRUE(host.ok()) << host.error();
    const HostDevice& hd = host.device();
    auto properties2 = reinterpret_cast<PFN_vkGetPhysicalDeviceProperties2>(
        hd.get_instance_proc_addr(hd.instance, "vkGetPhysicalDeviceProperties2"));
    VkPhysicalDeviceIDProperties id{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &id};
    properties2(hd.physical_device, &p2);

    Watch watch;
    SystemDesc desc = small_desc(watch);
    desc.snapshot = true;
    desc.exported_copies = 2;
    desc.device_uuid = id.deviceUUID;
    std::unique_ptr<System> system;
    ASSERT_TRUE(System::create(desc, system));
    ASSERT_TRUE(system->set_ambient({3.0f, 0.0f, 1.0f}));
    const Box box(1.0f);
    MeshId mesh = 0;
    InstanceId instance = 0;
    ASSERT_TRUE(system->create_mesh(box.desc(), mesh));
    ASSERT_TRUE(system->create_instance(mesh, translation(0.0f, 3.0f, 0.0f), false, instance));
    for (int i = 0; i < 5; ++i) {
        ASSERT_TRUE(system->step(1.0f / 60.0f));
        // The slots alternate as a host's frames would take them; the last step's lands in copy 1.
        ASSERT_TRUE(system->copy_wind_textures(std::uint32_t((i + 1) % 2)));
    }
    ExportedImage e;
    ASSERT_TRUE(system->export_wind_copy(0, 1, e));
    ASSERT_GE(e.fd, 0);
    const WindTexture& texture = system->wind_texture();
    EXPECT_EQ(e.extent[0], texture.extent[0]);
    EXPECT_EQ(e.extent[2], texture.extent[2]);
    EXPECT_EQ(e.format, VK_FORMAT_R16G16B16A16_SFLOAT);

    // The engine imports the copy: an image of the same parameters bound to the imported memory.
    VkDevice device = hd.device;
    VkExternalMemoryImageCreateInfo external;
    const VkImageCreateInfo info = import_image_info(e, external);
    VkImage image = VK_NULL_HANDLE;
    ASSERT_EQ(fn<PFN_vkCreateImage>(host, "vkCreateImage")(device, &info, nullptr, &image), VK_SUCCESS);
    VkMemoryDedicatedAllocateInfo dedicated{VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO};
    dedicated.image = image;
    VkImportMemoryFdInfoKHR import{VK_STRUCTURE_TYPE_IMPORT_MEMORY_FD_INFO_KHR, &dedicated};
    import.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    import.fd = e.fd;
    VkMemoryAllocateInfo allocation{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO, &import};
    allocation.allocationSize = e.allocation_size;
    allocation.memoryTypeIndex = e.memory_type_index;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    ASSERT_EQ(fn<PFN_vkAllocateMemory>(host, "vkAllocateMemory")(device, &allocation, nullptr, &memory),
              VK_SUCCESS);
    ASSERT_EQ(fn<PFN_vkBindImageMemory>(host, "vkBindImageMemory")(device, image, memory, 0), VK_SUCCESS);

    // A host-visible buffer the engine copies the texels into.
    const std::size_t cells = std::size_t(e.extent[0]) * e.extent[1] * e.extent[2];
    VkBufferCreateInfo buffer_info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    buffer_info.size = cells * 8;
    buffer_info.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    VkBuffer buffer = VK_NULL_HANDLE;
    ASSERT_EQ(fn<PFN_vkCreateBuffer>(host, "vkCreateBuffer")(device, &buffer_info, nullptr, &buffer),
              VK_SUCCESS);
    VkMemoryRequirements req;
    fn<PFN_vkGetBufferMemoryRequirements>(host, "vkGetBufferMemoryRequirements")(device, buffer, &req);
    auto memory_properties = reinterpret_cast<PFN_vkGetPhysicalDeviceMemoryProperties>(
        hd.get_instance_proc_addr(hd.instance, "vkGetPhysicalDeviceMemoryProperties"));
    VkPhysicalDeviceMemoryProperties types;
    memory_properties(hd.physical_device, &types);
    const VkMemoryPropertyFlags visible =
        VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
    VkMemoryAllocateInfo buffer_allocation{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    buffer_allocation.allocationSize = req.size;
    buffer_allocation.memoryTypeIndex = UINT32_MAX;
    for (std::uint32_t t = 0; t < types.memoryTypeCount && buffer_allocation.memoryTypeIndex == UINT32_MAX;
         ++t)
        if ((req.memoryTypeBits >> t & 1) && (types.memoryTypes[t].propertyFlags & visible) == visible)
            buffer_allocation.memoryTypeIndex = t;
    ASSERT_NE(buffer_allocation.memoryTypeIndex, UINT32_MAX);
    VkDeviceMemory buffer_memory = VK_NULL_HANDLE;
    ASSERT_EQ(fn<PFN_vkAllocateMemory>(host, "vkAllocateMemory")(device, &buffer_allocation, nullptr,
                                                                 &buffer_memory),
              VK_SUCCESS);
    ASSERT_EQ(fn<PFN_vkBindBufferMemory>(host, "vkBindBufferMemory")(device, buffer, buffer_memory, 0),
              VK_SUCCESS);

    // The engine acquires the copy from VK_QUEUE_FAMILY_EXTERNAL, in the layout gust released it in.
    struct Recording {
        const HostVulkan* host;
        VkImage image;
        VkBuffer buffer;
        VkExtent3D extent;
    } recording{&host, image, buffer, info.extent};
    ASSERT_TRUE(host.run(
        [](VkCommandBuffer cmd, void* user) {
            const auto& r = *static_cast<Recording*>(user);
            VkImageMemoryBarrier acquire{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
            acquire.dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
            acquire.oldLayout = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
            acquire.newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
            acquire.srcQueueFamilyIndex = VK_QUEUE_FAMILY_EXTERNAL;
            acquire.dstQueueFamilyIndex = r.host->device().queue_family;
            acquire.image = r.image;
            acquire.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
            fn<PFN_vkCmdPipelineBarrier>(*r.host, "vkCmdPipelineBarrier")(
                cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr, 0,
                nullptr, 1, &acquire);
            VkBufferImageCopy region{};
            region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
            region.imageExtent = r.extent;
            fn<PFN_vkCmdCopyImageToBuffer>(*r.host, "vkCmdCopyImageToBuffer")(
                cmd, r.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, r.buffer, 1, &region);
        },
        &recording));
    void* mapped = nullptr;
    ASSERT_EQ(fn<PFN_vkMapMemory>(host, "vkMapMemory")(device, buffer_memory, 0, VK_WHOLE_SIZE, 0, &mapped),
              VK_SUCCESS);
    std::vector<std::uint16_t> texels(cells * 4);
    std::memcpy(texels.data(), mapped, cells * 8);
    fn<PFN_vkUnmapMemory>(host, "vkUnmapMemory")(device, buffer_memory);

    // The snapshot of the same step at every cell centre (System::sample reads the same texels on the CPU).
    std::vector<Vec3> points, wind(cells);
    const float* m = texture.world_to_texture.m;
    for (std::uint32_t k = 0; k < e.extent[2]; ++k)
        for (std::uint32_t j = 0; j < e.extent[1]; ++j)
            for (std::uint32_t i = 0; i < e.extent[0]; ++i) {
                const float u = (float(i) + 0.5f) / float(e.extent[0]),
                            v = (float(j) + 0.5f) / float(e.extent[1]),
                            w = (float(k) + 0.5f) / float(e.extent[2]);
                points.push_back({(u - m[12]) / m[0], (v - m[13]) / m[5], (w - m[14]) / m[10]});
            }
    ASSERT_TRUE(system->sample(points, wind));
    std::size_t bad = 0;
    float fastest = 0.0f;
    for (std::size_t c = 0; c < cells; ++c) {
        const float got[3] = {from_half(texels[4 * c]), from_half(texels[4 * c + 1]),
                              from_half(texels[4 * c + 2])};
        const float want[3] = {wind[c].x, wind[c].y, wind[c].z};
        for (int a = 0; a < 3; ++a)
            if (std::abs(got[a] - want[a]) > std::abs(want[a]) * 0x1p-11f + 0x1p-24f) ++bad;
        fastest = std::max(fastest, std::sqrt(want[0] * want[0] + want[1] * want[1] + want[2] * want[2]));
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_GT(fastest, 3.0f); // the ambient 3.16 m/s, sped up beside the box: not a texture left empty

    fn<PFN_vkDestroyBuffer>(host, "vkDestroyBuffer")(device, buffer, nullptr);
    fn<PFN_vkFreeMemory>(host, "vkFreeMemory")(device, buffer_memory, nullptr);
    fn<PFN_vkDestroyImage>(host, "vkDestroyImage")(device, image, nullptr);
    fn<PFN_vkFreeMemory>(host, "vkFreeMemory")(device, memory, nullptr);
    EXPECT_EQ(host.messages(), 0);
    EXPECT_EQ(watch.errors, 0) << watch.last;
    EXPECT_EQ(watch.warnings, 0) << watch.last;
}

} // namespace
} // namespace gust::test
