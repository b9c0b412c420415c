// Draws the sample's world: meshes, instanced grass and swaying trees driven by gust's wind texture on the
// GPU, and the debug views (voxels, tree nodes, wind slice and arrows).
#pragma once

#include "views.hpp"
#include "vk_host.hpp"
#include "voxel_faces.hpp"
#include "world.hpp"

#include <cstdint>
#include <glm/glm.hpp>
#include <gust/gust.hpp>
#include <span>
#include <unordered_map>
#include <vector>

namespace sample {

/// A coloured line vertex (node boxes).
struct LineVertex {
    glm::vec3 position;
    glm::vec4 colour;
};

/// This frame's camera and wind, as the renderer needs them.
struct FrameView {
    glm::mat4 view_proj{1.0f};
    glm::vec3 eye{0.0f};
    float time = 0.0f;
    float dt = 0.0f;             ///< foliage step (s); 0 holds the foliage still
    glm::vec3 wind_origin{0.0f}; ///< min corner of gust's (finest) domain this frame (world, m)
    glm::vec3 ambient{0.0f};     ///< gust's ambient wind this frame, m/s
};

class Renderer {
  public:
    /// Pipelines for `colour_format`; the colour attachment ends each frame in `final_layout`.
    Renderer(VulkanHost& vk, const World& world, VkFormat colour_format, VkImageLayout final_layout);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    VkRenderPass render_pass() const { return pass_; }
    /// Binds gust's wind textures, finest first (System::wind_textures, 1..kWindCascades of them; read
    /// again each frame for their grids, so valid while the System lives), and its domain (again after the
    /// System is re-created). The GPU must be idle.
    void set_wind(std::span<const gust::WindTexture> textures, const gust::WindDomain& domain);
    /// Replaces the voxels drawn by the W view (ijk triples in the grid given, each once). The GPU must have
    /// finished the last frame.
    void set_voxels(const gust::VoxelGridInfo& grid, std::span<const gust::VoxelCoord> voxels);
    /// Replaces the node-box lines drawn by the R view.
    void set_lines(std::span<const LineVertex> lines);
    /// Uploads the skinned meshes' poses and the placements of this frame.
    void update_world(const World& world);

    /// Records the foliage update and the frame into `cmd` for a target image of `extent`; `hud` is called
    /// inside the render pass after the scene.
    template <class Hud>
    void record(VkCommandBuffer cmd, VkImageView target, VkExtent2D extent, const FrameView& view,
                const Views& views, Hud&& hud) {
        begin(cmd, target, extent, view, views);
        hud(cmd);
        vkCmdEndRenderPass(cmd);
    }
    /// Drops framebuffers and the depth buffer (after a swapchain re-creation). The GPU must be idle.
    void forget_targets();
    /// Mean and largest bend of the grass blades after the last frame (tip displacement over height).
    std::pair<float, float> grass_bend() const;
    /// Mean bend of the crowns in foliage `slots` after the last frame (tip displacement over height).
    float crown_bend(std::span<const std::uint32_t> slots) const;

  private:
    void begin(VkCommandBuffer cmd, VkImageView target, VkExtent2D extent, const FrameView& view,
               const Views& views);
    VkFramebuffer framebuffer(VkImageView target, VkExtent2D extent);
    VkPipeline compute(VkShaderModule shader);
    VkPipeline graphics(VkShaderModule vert, VkShaderModule frag, VkPrimitiveTopology topology,
                        bool mesh_input, bool line_input, bool depth_write, bool blend);
    void write_descriptors();

    VulkanHost& vk_;
    VkRenderPass pass_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline mesh_ = VK_NULL_HANDLE, grass_ = VK_NULL_HANDLE, voxels_ = VK_NULL_HANDLE,
               lines_ = VK_NULL_HANDLE, arrows_ = VK_NULL_HANDLE, slice_ = VK_NULL_HANDLE,
               foliage_ = VK_NULL_HANDLE, slice_fill_ = VK_NULL_HANDLE;
    Buffer uniforms_, seeds_, states_, lines_buffer_;
    std::uint32_t line_count_ = 0;
    std::uint32_t foliage_count_ = 0, grass_count_ = 0;
    VoxelFaces face_finder_;
    std::vector<VoxelFace> face_list_;
    Buffer faces_; ///< face_list_ for the W view's draw
    std::uint32_t face_count_ = 0;
    gust::VoxelGridInfo voxel_grid_{};
    std::span<const gust::WindTexture> wind_;
    Image slice_image_; ///< the T view's wind and air over the coarsest cascade (slice.comp)
    VkSampler slice_sampler_ = VK_NULL_HANDLE;
    gust::WindDomain domain_{};
    struct MeshBuffers {
        Buffer vertices, indices;
        std::uint32_t index_count = 0;
    };
    std::vector<MeshBuffers> meshes_;
    struct Draw {
        std::size_t mesh;
        bool solid; ///< hidden by Q
        glm::mat4 model;
        glm::vec4 colour;
        glm::vec4 sway;
    };
    std::vector<Draw> draws_;
    Image depth_;
    VkExtent2D depth_extent_{};
    std::unordered_map<VkImageView, VkFramebuffer> framebuffers_;
};

} // namespace sample
