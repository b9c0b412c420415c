// Detail that follows the device: the quality presets and how `auto` picks one (docs/sample.md).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vulkan/vulkan.h>

namespace sample {

/// How much the game asks of the device.
enum class Quality {
    Auto,   ///< picked from the device type (quality_for_device)
    Low,    ///< a CPU device (lavapipe): 15 fps or more on two cores
    Medium, ///< an integrated GPU
    High,   ///< a discrete GPU: a fine wind grid and a dense field
};

/// The most cascades the sample's shaders read (GUST_CASCADES in shaders/sample/sample_common.glsl).
inline constexpr std::uint32_t kMaxCascades = 4;

/// What a preset sets: gust's domain, the grass and the pressure budget.
struct Detail {
    std::array<std::uint32_t, 3> cells{}; ///< wind cells per axis
    float cell_size = 1.0f;               ///< wind cell edge, m
    std::uint32_t voxels_per_cell = 4;    ///< voxels per wind cell per axis (1, 2, 4 or 8)
    std::uint32_t grass_blades = 0;
    std::uint32_t max_cycles = 4; ///< pressure iterations per frame (the field carries over)
    std::uint32_t cascades = 3;   ///< nested wind grids around the focus, 1..kMaxCascades
    std::uint32_t ratio = 4;      ///< cell size from one cascade to the next coarser: 2 or 4
};

/// The values a command line gave explicitly; each replaces the preset's.
struct DetailOverrides {
    std::optional<std::array<std::uint32_t, 3>> cells;
    std::optional<float> cell_size;
    std::optional<std::uint32_t> voxels_per_cell;
    std::optional<std::uint32_t> grass_blades;
    std::optional<std::uint32_t> max_cycles;
    std::optional<std::uint32_t> cascades;
};

/// What `auto` picks for a device: CPU -> Low; discrete GPU -> High; integrated, virtual or other -> Medium.
Quality quality_for_device(VkPhysicalDeviceType type);
/// `quality`, with Auto resolved for a device of `type`.
Quality resolve(Quality quality, VkPhysicalDeviceType type);
/// The preset of a resolved quality (Auto: Medium's, the middle of the road).
Detail preset(Quality quality);
/// `detail` with the overrides that are set applied.
Detail apply(Detail detail, const DetailOverrides& overrides);
/// "auto", "low", "medium" or "high", as the command line spells them.
const char* quality_name(Quality quality);
/// The quality quality_name() spells as `name`, in any case; nothing for any other name.
std::optional<Quality> parse_quality(std::string_view name);
/// "a CPU device", "a discrete GPU", ...: the words `auto` decides on.
const char* device_type_words(VkPhysicalDeviceType type);

} // namespace sample
