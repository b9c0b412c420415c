// The pipeline cache: created from ContextDesc::pipeline_cache when that file is whole and holds this
// device's cache, and written back by Context::save_pipeline_cache().
#include <cstring>
#include <filesystem>
#include <fstream>
#include <gust/gpu/context.hpp>
#include <unistd.h>

namespace gust::gpu {

namespace {

/// The pipeline cache file: this header, then the blob vkGetPipelineCacheData gave. Vulkan must get the
/// blob back whole (its size as written), which its own header cannot tell, so a file cut short or
/// damaged is recognised by this one and never reaches the driver.
struct CacheFileHeader {
    char magic[8];
    std::uint64_t bytes;    ///< of the blob that follows
    std::uint64_t checksum; ///< fnv1a() of the blob
};
constexpr char kCacheMagic[8] = {'g', 'u', 's', 't', 'p', 'c', '0', '1'};

/// FNV-1a, 64 bits: enough to tell a damaged file from a good one (not an adversary's).
std::uint64_t fnv1a(const char* data, std::size_t bytes) {
    std::uint64_t hash = 14695981039346656037ull;
    for (std::size_t i = 0; i < bytes; ++i) {
        hash ^= static_cast<unsigned char>(data[i]);
        hash *= 1099511628211ull;
    }
    return hash;
}

/// The blob of a pipeline cache file when it is whole and holds the cache of the device `props`
/// describes; empty otherwise (no file, another format, cut short, damaged, another device or driver).
std::pmr::vector<char> read_pipeline_cache(const std::string& path, const VkPhysicalDeviceProperties& props,
                                           std::pmr::memory_resource* memory) {
    std::pmr::vector<char> file(memory);
    std::error_code ec;
    // A folder or a device file is no cache (and reading a folder throws).
    if (!std::filesystem::is_regular_file(path, ec)) return file;
    std::ifstream in(path, std::ios::binary);
    file.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    std::pmr::vector<char> blob(memory);
    CacheFileHeader header{};
    if (file.size() < sizeof(header)) return blob;
    std::memcpy(&header, file.data(), sizeof(header));
    const char* data = file.data() + sizeof(header);
    if (std::memcmp(header.magic, kCacheMagic, sizeof(kCacheMagic)) != 0 ||
        header.bytes != file.size() - sizeof(header) || header.checksum != fnv1a(data, header.bytes))
        return blob;
    // Vulkan's own header (VkPipelineCacheHeaderVersionOne) names the device and driver build.
    VkPipelineCacheHeaderVersionOne vk_header{};
    if (header.bytes < sizeof(vk_header)) return blob;
    std::memcpy(&vk_header, data, sizeof(vk_header));
    if (vk_header.headerVersion != VK_PIPELINE_CACHE_HEADER_VERSION_ONE ||
        vk_header.vendorID != props.vendorID || vk_header.deviceID != props.deviceID ||
        std::memcmp(vk_header.pipelineCacheUUID, props.pipelineCacheUUID, VK_UUID_SIZE) != 0)
        return blob;
    blob.assign(data, data + header.bytes);
    return blob;
}

} // namespace

Status Context::create_pipeline_cache(const VkPhysicalDeviceProperties& props) {
    // A stale, foreign or damaged file costs nothing but the compile.
    std::pmr::vector<char> blob(host_memory_);
    if (!pipeline_cache_path_.empty())
        blob = read_pipeline_cache(std::string(pipeline_cache_path_), props, host_memory_);
    VkPipelineCacheCreateInfo cache_info{VK_STRUCTURE_TYPE_PIPELINE_CACHE_CREATE_INFO};
    cache_info.initialDataSize = blob.size();
    cache_info.pInitialData = blob.empty() ? nullptr : blob.data();
    if (VkResult r = vk_.vkCreatePipelineCache(device_, &cache_info, allocator(), &pipeline_cache_);
        r != VK_SUCCESS)
        return Status::failure(std::string("vkCreatePipelineCache failed: ") + to_string(r));
    name(VK_OBJECT_TYPE_PIPELINE_CACHE, std::uint64_t(pipeline_cache_), "gust pipeline cache");
    pipeline_cache_loaded_ = !blob.empty();
    return {};
}

Status Context::save_pipeline_cache() const {
    if (pipeline_cache_path_.empty() || !pipeline_cache_) return {};
    std::size_t bytes = 0;
    if (VkResult r = vk_.vkGetPipelineCacheData(device_, pipeline_cache_, &bytes, nullptr); r != VK_SUCCESS)
        return Status::failure(std::string("vkGetPipelineCacheData failed: ") + to_string(r));
    std::pmr::vector<char> blob(bytes, host_memory_);
    if (VkResult r = vk_.vkGetPipelineCacheData(device_, pipeline_cache_, &bytes, blob.data());
        r != VK_SUCCESS)
        return Status::failure(std::string("vkGetPipelineCacheData failed: ") + to_string(r));
    // Written beside the file under a name of this process's own and renamed over it, so that a reader
    // never sees half a cache, nor two writers one file.
    const std::filesystem::path path{std::string(pipeline_cache_path_)};
    std::error_code ec;
    // Only a missing or empty file, or one of ours (whole or damaged), is replaced: a path that names
    // anything else is a mistake, and the file is the user's.
    if (std::filesystem::exists(path, ec)) {
        if (!std::filesystem::is_regular_file(path, ec))
            return Status::failure(path.string() + ": not a regular file, so no pipeline cache was written");
        char magic[sizeof(kCacheMagic)] = {};
        std::ifstream in(path, std::ios::binary);
        in.read(magic, sizeof(magic));
        if (in.gcount() > 0 && (in.gcount() < std::streamsize(sizeof(magic)) ||
                                std::memcmp(magic, kCacheMagic, sizeof(magic)) != 0))
            return Status::failure(path.string() + ": not a gust pipeline cache, so it was left as it is");
    }
    if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
    const std::filesystem::path partial = path.string() + "." + std::to_string(getpid()) + ".partial";
    CacheFileHeader header{};
    std::memcpy(header.magic, kCacheMagic, sizeof(kCacheMagic));
    header.bytes = bytes;
    header.checksum = fnv1a(blob.data(), bytes);
    {
        std::ofstream out(partial, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(&header), sizeof(header));
        out.write(blob.data(), std::streamsize(bytes));
        if (!out) {
            out.close();
            std::filesystem::remove(partial, ec);
            return Status::failure(partial.string() + ": cannot write the pipeline cache");
        }
    }
    std::filesystem::rename(partial, path, ec);
    if (ec) {
        std::error_code ignored;
        std::filesystem::remove(partial, ignored);
        return Status::failure(path.string() + ": cannot write the pipeline cache (" + ec.message() + ")");
    }
    return {};
}

} // namespace gust::gpu
