#include "quality.hpp"

#include <algorithm>
#include <cctype>

namespace sample {

Quality quality_for_device(VkPhysicalDeviceType type) {
    switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return Quality::Low;
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return Quality::High;
    default:
        return Quality::Medium;
    }
}

Quality resolve(Quality quality, VkPhysicalDeviceType type) {
    return quality == Quality::Auto ? quality_for_device(type) : quality;
}

Detail preset(Quality quality) {
    switch (quality) {
    case Quality::Low:
        // Measured on lavapipe (docs/sample.md): the grid and grass of the old defaults, with voxels of
        // 0.44 m instead of 0.875 m so that the characters are more than one block; a bigger grid costs
        // lavapipe more in per-dispatch overhead than finer voxels do. Three cascades of ratio 4 reach
        // 448 m across, the valley around the village.
        return {{16, 8, 16}, 1.75f, 4, 20000, 8, 3, 4};
    case Quality::High:
        // About 0.5 m cells and 0.125 m voxels over 32 m x 12 m x 32 m: the fox is six voxels tall.
        // Four cascades of ratio 4 reach 2 km across.
        return {{64, 24, 64}, 0.5f, 4, 200000, 16, 4, 4};
    case Quality::Auto:
    case Quality::Medium:
        break;
    }
    return {{32, 12, 32}, 1.0f, 4, 60000, 8, 3, 4};
}

Detail apply(Detail detail, const DetailOverrides& overrides) {
    if (overrides.cells) detail.cells = *overrides.cells;
    if (overrides.cell_size) detail.cell_size = *overrides.cell_size;
    if (overrides.voxels_per_cell) detail.voxels_per_cell = *overrides.voxels_per_cell;
    if (overrides.grass_blades) detail.grass_blades = *overrides.grass_blades;
    if (overrides.max_cycles) detail.max_cycles = *overrides.max_cycles;
    if (overrides.cascades) detail.cascades = *overrides.cascades;
    return detail;
}

const char* quality_name(Quality quality) {
    switch (quality) {
    case Quality::Low:
        return "low";
    case Quality::Medium:
        return "medium";
    case Quality::High:
        return "high";
    case Quality::Auto:
        break;
    }
    return "auto";
}

std::optional<Quality> parse_quality(std::string_view name) {
    for (Quality q : {Quality::Auto, Quality::Low, Quality::Medium, Quality::High}) {
        const std::string_view spelled = quality_name(q);
        if (std::equal(name.begin(), name.end(), spelled.begin(), spelled.end(),
                       [](char a, char b) { return std::tolower(static_cast<unsigned char>(a)) == b; }))
            return q;
    }
    return std::nullopt;
}

const char* device_type_words(VkPhysicalDeviceType type) {
    switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
        return "a CPU device";
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
        return "a discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
        return "an integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
        return "a virtual GPU";
    default:
        return "a device of another type";
    }
}

} // namespace sample
