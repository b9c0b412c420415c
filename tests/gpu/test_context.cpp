#include "support/gpu_env.hpp"

#include <cstring>
#include <gtest/gtest.h>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/image.hpp>
#include <gust/gpu/profiler.hpp>
#include <numeric>
#include <vector>

namespace gust::test {
namespace {

using ContextTest = GpuTest;

TEST_F(ContextTest, picksAVulkan13DeviceWithAGraphicsComputeQueue) {
    EXPECT_FALSE(ctx().info().name.empty());
    EXPECT_GE(ctx().info().api_version, VK_API_VERSION_1_3);
    EXPECT_NE(ctx().device(), VK_NULL_HANDLE);
    EXPECT_NE(ctx().queue(), VK_NULL_HANDLE);
    EXPECT_FALSE(ctx().device_names().empty());
}

TEST(ContextCreation, overrideByNameSelectsThatDevice) {
    gpu::ContextDesc desc;
    desc.device = gpu_context().info().name.substr(0, 4);
    auto ctx = gpu::Context::create(desc);
    ASSERT_TRUE(ctx) << ctx.message();
    EXPECT_EQ((*ctx)->info().name, gpu_context().info().name);
}

TEST(ContextCreation, overrideMatchingNoDeviceFailsListingTheDevices) {
    gpu::ContextDesc desc;
    desc.device = "no-such-gpu-xyz";
    auto ctx = gpu::Context::create(desc);
    ASSERT_FALSE(ctx);
    EXPECT_NE(ctx.message().find("no-such-gpu-xyz"), std::string::npos);
    EXPECT_NE(ctx.message().find(gpu_context().info().name), std::string::npos);
}

TEST(ContextCreation, validationMessagesAreCountedAndForwarded) {
    gpu::ContextDesc desc;
    desc.validation = true;
    int forwarded = 0;
    desc.on_message = [&](gpu::Severity severity, const std::string&) {
        forwarded += severity == gpu::Severity::Error;
    };
    auto ctx = gpu::Context::create(desc);
    ASSERT_TRUE(ctx) << ctx.message();
    gpu::Context& c = **ctx;
    // Deliberate misuse: a zero-sized buffer violates VUID-VkBufferCreateInfo-size-00912.
    VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
    info.size = 0;
    info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
    VkBuffer buffer = VK_NULL_HANDLE;
    c.vk().vkCreateBuffer(c.device(), &info, nullptr, &buffer);
    if (buffer) c.vk().vkDestroyBuffer(c.device(), buffer, nullptr);
    EXPECT_GE(c.validation_messages(), 1u);
    EXPECT_GE(forwarded, 1);
    EXPECT_NE(c.last_validation_message().find("size"), std::string::npos);
}

using BufferTest = GpuTest;

TEST_F(BufferTest, uploadThenDownloadRoundTrips) {
    std::vector<std::uint32_t> data(10000);
    std::iota(data.begin(), data.end(), 7u);
    auto buffer = gpu::Buffer::create(ctx(), data.size() * 4, gpu::MemoryUse::Device);
    ASSERT_TRUE(buffer) << buffer.message();
    EXPECT_NE(buffer->address(), 0u);
    ASSERT_TRUE(gpu::upload(ctx(), *buffer, data.data(), data.size() * 4));
    std::vector<std::uint32_t> back(data.size());
    ASSERT_TRUE(gpu::download(ctx(), *buffer, back.data(), back.size() * 4));
    EXPECT_EQ(back, data);
}

TEST_F(BufferTest, rejectsZeroSizeAndOutOfRangeCopies) {
    EXPECT_FALSE(gpu::Buffer::create(ctx(), 0, gpu::MemoryUse::Device));
    auto buffer = gpu::Buffer::create(ctx(), 16, gpu::MemoryUse::Upload);
    ASSERT_TRUE(buffer);
    std::uint32_t v[8] = {};
    EXPECT_FALSE(gpu::upload(ctx(), *buffer, v, sizeof(v)));
    EXPECT_FALSE(gpu::download(ctx(), *buffer, v, 8, 12));
}

TEST_F(BufferTest, fillRecordedOnTheGpuIsVisibleAfterSubmit) {
    auto buffer = gpu::Buffer::create(ctx(), 256, gpu::MemoryUse::Readback);
    ASSERT_TRUE(buffer);
    auto profiler = gpu::Profiler::create(ctx());
    ASSERT_TRUE(profiler);
    ASSERT_TRUE(ctx().submit_and_wait([&](VkCommandBuffer cmd) {
        profiler->reset(cmd);
        profiler->begin(cmd, "fill");
        ctx().vk().vkCmdFillBuffer(cmd, buffer->handle(), 0, VK_WHOLE_SIZE, 0xabcdef01u);
        profiler->end(cmd);
    }));
    std::uint32_t word = 0;
    ASSERT_TRUE(gpu::download(ctx(), *buffer, &word, 4, 252));
    EXPECT_EQ(word, 0xabcdef01u);
    if (ctx().info().timestamp_period_ns > 0.0f) {
        auto passes = profiler->read();
        ASSERT_EQ(passes.size(), 1u);
        EXPECT_EQ(passes[0].first, "fill");
        EXPECT_GE(passes[0].second, 0.0);
    }
}

using ImageTest = GpuTest;

TEST_F(ImageTest, volumeRoundTripsThroughBufferCopies) {
    gpu::ImageDesc desc;
    desc.extent = {5, 4, 3};
    auto image = gpu::Image::create(ctx(), desc);
    ASSERT_TRUE(image) << image.message();
    EXPECT_NE(image->view(), VK_NULL_HANDLE);
    std::vector<float> texels(5 * 4 * 3 * 4);
    std::iota(texels.begin(), texels.end(), -10.0f);
    const VkDeviceSize bytes = texels.size() * sizeof(float);
    auto src = gpu::Buffer::create(ctx(), bytes, gpu::MemoryUse::Upload);
    auto dst = gpu::Buffer::create(ctx(), bytes, gpu::MemoryUse::Readback);
    ASSERT_TRUE(src && dst);
    ASSERT_TRUE(gpu::upload(ctx(), *src, texels.data(), bytes));
    ASSERT_TRUE(ctx().submit_and_wait([&](VkCommandBuffer cmd) {
        image->transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
        image->copy_from(cmd, *src);
        image->transition(cmd, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
        image->copy_to(cmd, *dst);
    }));
    std::vector<float> back(texels.size());
    ASSERT_TRUE(gpu::download(ctx(), *dst, back.data(), bytes));
    EXPECT_EQ(back, texels);
    EXPECT_EQ(image->layout(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
}

TEST_F(ImageTest, rejectsZeroExtent) {
    gpu::ImageDesc desc;
    desc.extent = {4, 0, 1};
    EXPECT_FALSE(gpu::Image::create(ctx(), desc));
}

} // namespace
} // namespace gust::test
