// Compute and graphics pipelines from embedded SPIR-V. Shaders take every buffer by device address
// through push constants, so no pipeline here has descriptor sets.
#pragma once

#include <cstdint>
#include <gust/gpu/context.hpp>
#include <span>

namespace gust::gpu {

/// Fixed-function choices for a graphics pipeline that renders without attachments.
struct GraphicsPipelineDesc {
    std::span<const std::uint32_t> vertex;   ///< SPIR-V words
    std::span<const std::uint32_t> geometry; ///< optional (empty: no geometry stage)
    std::span<const std::uint32_t> fragment; ///< SPIR-V words
    std::uint32_t push_constant_bytes = 0;
    /// Specialization constants for every stage: value i goes to constant_id i.
    std::span<const std::uint32_t> constants;
};

/// A pipeline and its layout. Move-only.
class Pipeline {
  public:
    Pipeline() = default;
    /// A compute pipeline named `name` (for capture tools; a literal) with `push_constant_bytes` of push
    /// constants (entry point "main"); `constants[i]` specializes constant_id i.
    static Result<Pipeline> compute(Context& ctx, const char* name, std::span<const std::uint32_t> spirv,
                                    std::uint32_t push_constant_bytes,
                                    std::span<const std::uint32_t> constants = {});
    /// A graphics pipeline with no vertex input, no attachments and dynamic viewport and scissor.
    static Result<Pipeline> graphics(Context& ctx, const char* name, const GraphicsPipelineDesc& desc);
    ~Pipeline();
    Pipeline(Pipeline&& other) noexcept;
    Pipeline& operator=(Pipeline&& other) noexcept;
    Pipeline(const Pipeline&) = delete;
    Pipeline& operator=(const Pipeline&) = delete;

    /// Binds the pipeline and pushes `bytes` of constants (all stages).
    void bind(VkCommandBuffer cmd, const void* push, std::uint32_t bytes) const;
    /// vkCmdDispatch, counted in the Context's work (every dispatch of gust goes through these three) and
    /// timed under the pipeline's name while the Context times dispatches (Context::time_dispatches).
    void dispatch(VkCommandBuffer cmd, std::uint32_t x, std::uint32_t y = 1, std::uint32_t z = 1) const;
    /// vkCmdDispatchIndirect, counted alike (an emptied one still costs its dispatch).
    void dispatch_indirect(VkCommandBuffer cmd, VkBuffer arguments, VkDeviceSize offset) const;
    /// vkCmdDraw of `vertices` vertices, one instance, counted alike.
    void draw(VkCommandBuffer cmd, std::uint32_t vertices) const;
    VkPipeline handle() const { return pipeline_; }
    VkPipelineLayout layout() const { return layout_; }

  private:
    Context* ctx_ = nullptr;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipelineBindPoint bind_point_ = VK_PIPELINE_BIND_POINT_COMPUTE;
    const char* name_ = ""; ///< the literal it was created with (Context::time_dispatches)
    void release();
    /// Times the work recorded by `record` apart when the Context times dispatches.
    template <class Record> void timed(VkCommandBuffer cmd, Record record) const;
    Status create_layout(std::uint32_t push_constant_bytes);
};

} // namespace gust::gpu
