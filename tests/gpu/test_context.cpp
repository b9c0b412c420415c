#include "support/gpu_env.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/image.hpp>
#include <gust/gpu/profiler.hpp>
#include <numeric>
#include <string>
#include <unistd.h>
#include <vector>

namespace gust::test {
namespace {

using ContextTest = GpuTest;

TEST_F(ContextTest, picksAVulkan12DeviceWithAGraphicsComputeQueue) {
    EXPECT_FALSE(ctx().info().name.empty());
    EXPECT_GE(ctx().info().api_version, VK_API_VERSION_1_2);
    EXPECT_NE(ctx().device(), VK_NULL_HANDLE);
    EXPECT_NE(ctx().queue(), VK_NULL_HANDLE);
    EXPECT_FALSE(ctx().device_names().empty());
}

VkQueueFamilyProperties family(VkQueueFlags flags, std::uint32_t queues = 1) {
    VkQueueFamilyProperties f{};
    f.queueFlags = flags;
    f.queueCount = queues;
    return f;
}
constexpr VkQueueFlags kG = VK_QUEUE_GRAPHICS_BIT, kC = VK_QUEUE_COMPUTE_BIT, kT = VK_QUEUE_TRANSFER_BIT;

// Issue 41: gust takes a compute-only family when it does not need the raster voxelizer.
TEST(QueueFamily, anAsyncComputeFamilyIsPickedUnlessGraphicsIsNeeded) {
    // NVIDIA's list: graphics+compute+transfer, transfer only, compute+transfer.
    const VkQueueFamilyProperties nvidia[] = {family(kG | kC | kT, 16), family(kT, 2), family(kC | kT, 8)};
    EXPECT_EQ(gpu::pick_queue_family(nvidia, false), 2u);
    EXPECT_EQ(gpu::pick_queue_family(nvidia, true), 0u);
    // AMD's: the async compute family comes second, before a transfer (DMA) family.
    const VkQueueFamilyProperties amd[] = {family(kG | kC | kT), family(kC | kT, 4), family(kT, 2)};
    EXPECT_EQ(gpu::pick_queue_family(amd, false), 1u);
    EXPECT_EQ(gpu::pick_queue_family(amd, true), 0u);
}

TEST(QueueFamily, aSingleGraphicsAndComputeFamilyServesBoth) {
    const VkQueueFamilyProperties lavapipe[] = {family(kG | kC | kT)};
    EXPECT_EQ(gpu::pick_queue_family(lavapipe, false), 0u);
    EXPECT_EQ(gpu::pick_queue_family(lavapipe, true), 0u);
}

TEST(QueueFamily, familiesWithoutComputeOrQueuesNeverFit) {
    const VkQueueFamilyProperties transfer_only[] = {family(kT)};
    EXPECT_FALSE(gpu::pick_queue_family(transfer_only, false));
    EXPECT_FALSE(gpu::pick_queue_family(transfer_only, true));
    EXPECT_FALSE(gpu::pick_queue_family({}, false));
    // A compute accelerator: no graphics anywhere, so only a caller without the raster path fits.
    const VkQueueFamilyProperties accelerator[] = {family(kT), family(kC | kT)};
    EXPECT_EQ(gpu::pick_queue_family(accelerator, false), 1u);
    EXPECT_FALSE(gpu::pick_queue_family(accelerator, true));
    // Graphics without compute does not fit; nor does a family that lists no queues.
    const VkQueueFamilyProperties odd[] = {family(kG), family(kC, 0), family(kG | kC)};
    EXPECT_EQ(gpu::pick_queue_family(odd, false), 2u);
    EXPECT_EQ(gpu::pick_queue_family(odd, true), 2u);
}

// On the test's device: without graphics needed, the first compute-only family if it has one, else the first
// graphics+compute one (lavapipe's only family); info() says which kind it is.
TEST(ContextCreation, withoutGraphicsNeededRunsOnTheDevicesAsyncComputeFamilyIfAny) {
    gpu::ContextDesc desc;
    desc.validation = true;
    desc.device = gpu_context().info().name;
    desc.needs_graphics = false;
    auto created = gpu::Context::create(desc);
    ASSERT_TRUE(created) << created.message();
    gpu::Context& ctx = **created;
    std::uint32_t count = 0;
    ctx.vk().vkGetPhysicalDeviceQueueFamilyProperties(ctx.physical_device(), &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    ctx.vk().vkGetPhysicalDeviceQueueFamilyProperties(ctx.physical_device(), &count, families.data());
    const auto first = [&](VkQueueFlags flags) {
        for (std::uint32_t i = 0; i < count; ++i)
            if ((families[i].queueFlags & (kG | kC)) == flags && families[i].queueCount > 0) return i;
        return count;
    };
    std::uint32_t expected = first(kC);
    if (expected == count) expected = first(kG | kC);
    ASSERT_LT(expected, count);
    EXPECT_EQ(ctx.queue_family(), expected);
    EXPECT_EQ(ctx.info().graphics_queue, (families[expected].queueFlags & kG) != 0);
    EXPECT_TRUE(gpu_context().info().graphics_queue) << "the default Context keeps graphics";
    EXPECT_EQ(ctx.validation_messages(), 0u) << ctx.last_validation_message();
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

// ContextDesc::device_uuid: the device another VkDevice runs on (an engine importing gust's memory).
TEST(ContextCreation, deviceUuidSelectsThatDeviceAndAnUnknownOneFailsListingTheDevices) {
    const gpu::Context& shared = gpu_context();
    VkPhysicalDeviceIDProperties id{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &id};
    shared.vk().vkGetPhysicalDeviceProperties2(shared.physical_device(), &p2);
    gpu::ContextDesc desc;
    desc.device = "no-such-gpu-xyz"; // the UUID comes first
    desc.device_uuid.emplace();
    std::memcpy(desc.device_uuid->data(), id.deviceUUID, VK_UUID_SIZE);
    desc.external_memory = true;
    auto ctx = gpu::Context::create(desc);
    ASSERT_TRUE(ctx) << ctx.message();
    EXPECT_EQ((*ctx)->info().name, shared.info().name);
    EXPECT_TRUE((*ctx)->external_memory());
    // An exportable image hands out a descriptor of its memory.
    gpu::ImageDesc image_desc;
    image_desc.extent = {4, 4, 4};
    image_desc.format = VK_FORMAT_R16G16B16A16_SFLOAT;
    image_desc.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    image_desc.exportable = true;
    auto image = gpu::Image::create(**ctx, image_desc);
    ASSERT_TRUE(image) << image.message();
    EXPECT_GE(image->allocation_size(), VkDeviceSize(4 * 4 * 4 * 8));
    auto fd = image->export_fd();
    ASSERT_TRUE(fd) << fd.message();
    EXPECT_GE(*fd, 0);
    close(*fd);
    // Without external_memory an exportable image is refused, naming the extension.
    EXPECT_FALSE(shared.external_memory());
    auto refused = gpu::Image::create(gpu_context(), image_desc);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.message().find("VK_KHR_external_memory_fd"), std::string::npos);

    desc.device_uuid->fill(0xee);
    auto none = gpu::Context::create(desc);
    ASSERT_FALSE(none);
    EXPECT_NE(none.message().find("deviceUUID"), std::string::npos);
    EXPECT_NE(none.message().find(shared.info().name), std::string::npos);
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

namespace fs = std::filesystem;

/// An empty folder of this test process's own under the temp directory.
fs::path fresh_folder(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("gust_gpu_" + name + "_" + std::to_string(getpid()));
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string read_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary | std::ios::trunc)
        .write(bytes.data(), std::streamsize(bytes.size()));
}

/// A validated Context whose pipeline cache lives in `file`.
std::unique_ptr<gpu::Context> context_with_cache(const fs::path& file) {
    gpu::ContextDesc desc;
    desc.validation = true;
    desc.pipeline_cache = file.string();
    auto ctx = gpu::Context::create(desc);
    EXPECT_TRUE(ctx) << ctx.message();
    return ctx ? std::move(*ctx) : nullptr;
}

/// FNV-1a over 64 bits, as the cache file's header states its blob's checksum (docs/cli.md).
std::uint64_t fnv1a(const std::string& bytes) {
    std::uint64_t hash = 14695981039346656037ull;
    for (char c : bytes) {
        hash ^= static_cast<unsigned char>(c);
        hash *= 1099511628211ull;
    }
    return hash;
}

TEST(PipelineCacheFile, isWrittenWholeIntoItsFolderAndGivenToTheNextContext) {
    const fs::path folder = fresh_folder("cache_written");
    const fs::path file = folder / "gust" / "pipelines.bin";
    auto first = context_with_cache(file);
    ASSERT_TRUE(first);
    EXPECT_FALSE(first->pipeline_cache_loaded()) << "there was no file yet";
    ASSERT_TRUE(first->save_pipeline_cache());
    // gust's header (8-byte tag, size, checksum), then at least Vulkan's 32-byte header.
    EXPECT_GE(fs::file_size(file), 24u + 32u);
    EXPECT_EQ(std::distance(fs::directory_iterator(file.parent_path()), fs::directory_iterator()), 1)
        << "the file is written under another name and renamed: nothing else is left beside it";
    auto second = context_with_cache(file);
    ASSERT_TRUE(second);
    EXPECT_TRUE(second->pipeline_cache_loaded());
    EXPECT_EQ(second->validation_messages(), 0u);
    fs::remove_all(folder);
}

TEST(PipelineCacheFile, cutShortDamagedOrForeignIsIgnoredAndReplacedOnlyWhenItIsACache) {
    const fs::path folder = fresh_folder("cache_damaged");
    const fs::path file = folder / "pipelines.bin";
    {
        auto ctx = context_with_cache(file);
        ASSERT_TRUE(ctx);
        ASSERT_TRUE(ctx->save_pipeline_cache());
    }
    const std::string good = read_bytes(file);
    ASSERT_GE(good.size(), 24u + 32u);
    std::string flipped = good;
    flipped[good.size() - 1] = char(flipped[good.size() - 1] ^ 0x10);
    std::string garbage(4096, '\0');
    for (std::size_t i = 0; i < garbage.size(); ++i)
        garbage[i] = char((i * 2654435761u) >> 13);
    // Whole and well formed, but Vulkan's header names another vendor (offset 8 of the blob).
    std::string foreign = good.substr(24);
    foreign[8] = char(foreign[8] ^ 0x5a);
    std::string foreign_file = good.substr(0, 8);
    const std::uint64_t words[2] = {foreign.size(), fnv1a(foreign)};
    foreign_file.append(reinterpret_cast<const char*>(words), sizeof(words));
    foreign_file += foreign;
    const std::pair<const char*, std::string> cases[] = {{"empty", ""},
                                                         {"shorter than the header", good.substr(0, 10)},
                                                         {"cut by one byte", good.substr(0, good.size() - 1)},
                                                         {"cut in half", good.substr(0, good.size() / 2)},
                                                         {"one bit flipped", flipped},
                                                         {"garbage", garbage},
                                                         {"Vulkan's blob alone", good.substr(24)},
                                                         {"another device's", foreign_file}};
    for (const auto& [name, bytes] : cases) {
        write_bytes(file, bytes);
        auto ctx = context_with_cache(file);
        ASSERT_TRUE(ctx) << name;
        EXPECT_FALSE(ctx->pipeline_cache_loaded()) << name;
        EXPECT_EQ(ctx->validation_messages(), 0u) << name << ": " << ctx->last_validation_message();
        // A gust cache, however damaged, or an empty file is replaced; any other file may be the user's.
        if (bytes.empty() || bytes.rfind("gustpc01", 0) == 0) {
            ASSERT_TRUE(ctx->save_pipeline_cache()) << name;
            EXPECT_EQ(read_bytes(file), good) << name << " is replaced by this device's cache";
        } else {
            const Status saved = ctx->save_pipeline_cache();
            EXPECT_FALSE(saved) << name;
            EXPECT_NE(saved.message().find(file.string()), std::string::npos) << saved.message();
            EXPECT_EQ(read_bytes(file), bytes) << name << " is left as it is";
        }
    }
    fs::remove_all(folder);
}

TEST(PipelineCacheFile, thatCannotBeWrittenFailsNamingIt) {
    const fs::path folder = fresh_folder("cache_unwritable");
    write_bytes(folder / "a_file", "not a folder");
    const fs::path file = folder / "a_file" / "pipelines.bin";
    auto ctx = context_with_cache(file);
    ASSERT_TRUE(ctx) << "a cache that cannot be read is no reason to fail";
    EXPECT_FALSE(ctx->pipeline_cache_loaded());
    const Status saved = ctx->save_pipeline_cache();
    ASSERT_FALSE(saved);
    EXPECT_NE(saved.message().find("a_file"), std::string::npos) << saved.message();
    fs::remove_all(folder);
}

TEST(PipelineCacheFile, thatNamesAFolderIsNoCacheAndTheFolderIsLeftAlone) {
    const fs::path folder = fresh_folder("cache_is_a_folder");
    write_bytes(folder / "inside", "the user's");
    auto ctx = context_with_cache(folder);
    ASSERT_TRUE(ctx) << "reading a folder threw, and the System's creation failed with DeviceFailure";
    EXPECT_FALSE(ctx->pipeline_cache_loaded());
    const Status saved = ctx->save_pipeline_cache();
    ASSERT_FALSE(saved);
    EXPECT_NE(saved.message().find("not a regular file"), std::string::npos) << saved.message();
    EXPECT_EQ(read_bytes(folder / "inside"), "the user's");
    fs::remove_all(folder);
}

} // namespace
} // namespace gust::test
