#include <gust/gpu/pipeline.hpp>
#include <gust/gpu/profiler.hpp>
#include <memory_resource>
#include <utility>
#include <vector>

namespace gust::gpu {

namespace {

Result<VkShaderModule> make_module(Context& ctx, std::span<const std::uint32_t> spirv) {
    VkShaderModuleCreateInfo info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    info.codeSize = spirv.size_bytes();
    info.pCode = spirv.data();
    VkShaderModule module = VK_NULL_HANDLE;
    if (VkResult r = ctx.vk().vkCreateShaderModule(ctx.device(), &info, ctx.allocator(), &module);
        r != VK_SUCCESS)
        return Result<VkShaderModule>::failure(std::string("vkCreateShaderModule failed: ") + to_string(r));
    return module;
}

/// Specialization info mapping constants[i] to constant_id i (entries owned by the caller).
VkSpecializationInfo specialization(std::span<const std::uint32_t> constants,
                                    std::pmr::vector<VkSpecializationMapEntry>& entries) {
    entries.clear();
    for (std::uint32_t i = 0; i < constants.size(); ++i)
        entries.push_back({i, i * std::uint32_t(sizeof(std::uint32_t)), sizeof(std::uint32_t)});
    VkSpecializationInfo info{};
    info.mapEntryCount = std::uint32_t(entries.size());
    info.pMapEntries = entries.data();
    info.dataSize = constants.size_bytes();
    info.pData = constants.data();
    return info;
}

} // namespace

Status Pipeline::create_layout(std::uint32_t push_constant_bytes) {
    VkPushConstantRange range{VK_SHADER_STAGE_ALL, 0, push_constant_bytes};
    VkPipelineLayoutCreateInfo info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    info.pushConstantRangeCount = push_constant_bytes ? 1 : 0;
    info.pPushConstantRanges = &range;
    if (VkResult r = ctx_->vk().vkCreatePipelineLayout(ctx_->device(), &info, ctx_->allocator(), &layout_);
        r != VK_SUCCESS)
        return Status::failure(std::string("vkCreatePipelineLayout failed: ") + to_string(r));
    return {};
}

Result<Pipeline> Pipeline::compute(Context& ctx, const char* name, std::span<const std::uint32_t> spirv,
                                   std::uint32_t push_constant_bytes,
                                   std::span<const std::uint32_t> constants) {
    Pipeline p;
    p.ctx_ = &ctx;
    p.name_ = name;
    p.bind_point_ = VK_PIPELINE_BIND_POINT_COMPUTE;
    if (Status s = p.create_layout(push_constant_bytes); !s) return s;
    ctx.name(VK_OBJECT_TYPE_PIPELINE_LAYOUT, std::uint64_t(p.layout_), name);
    auto module = make_module(ctx, spirv);
    if (!module) return module.status();
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = *module;
    info.stage.pName = "main";
    std::pmr::vector<VkSpecializationMapEntry> entries(ctx.memory());
    const VkSpecializationInfo spec = specialization(constants, entries);
    info.stage.pSpecializationInfo = constants.empty() ? nullptr : &spec;
    info.layout = p.layout_;
    VkResult r = ctx.vk().vkCreateComputePipelines(ctx.device(), ctx.pipeline_cache(), 1, &info,
                                                   ctx.allocator(), &p.pipeline_);
    ctx.vk().vkDestroyShaderModule(ctx.device(), *module, ctx.allocator());
    if (r != VK_SUCCESS)
        return Result<Pipeline>::failure(std::string("vkCreateComputePipelines failed: ") + to_string(r));
    ctx.name(VK_OBJECT_TYPE_PIPELINE, std::uint64_t(p.pipeline_), name);
    return p;
}

Result<Pipeline> Pipeline::graphics(Context& ctx, const char* name, const GraphicsPipelineDesc& desc) {
    Pipeline p;
    p.ctx_ = &ctx;
    p.name_ = name;
    p.bind_point_ = VK_PIPELINE_BIND_POINT_GRAPHICS;
    if (Status s = p.create_layout(desc.push_constant_bytes); !s) return s;
    ctx.name(VK_OBJECT_TYPE_PIPELINE_LAYOUT, std::uint64_t(p.layout_), name);

    std::pmr::vector<VkPipelineShaderStageCreateInfo> stages(ctx.memory());
    std::pmr::vector<VkShaderModule> modules(ctx.memory());
    std::pmr::vector<VkSpecializationMapEntry> entries(ctx.memory());
    const VkSpecializationInfo spec = specialization(desc.constants, entries);
    auto add = [&](std::span<const std::uint32_t> code, VkShaderStageFlagBits stage) -> Status {
        if (code.empty()) return {};
        auto m = make_module(ctx, code);
        if (!m) return m.status();
        modules.push_back(*m);
        VkPipelineShaderStageCreateInfo s{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
        s.stage = stage;
        s.module = *m;
        s.pName = "main";
        s.pSpecializationInfo = desc.constants.empty() ? nullptr : &spec;
        stages.push_back(s);
        return {};
    };
    Status status = add(desc.vertex, VK_SHADER_STAGE_VERTEX_BIT);
    if (status) status = add(desc.geometry, VK_SHADER_STAGE_GEOMETRY_BIT);
    if (status) status = add(desc.fragment, VK_SHADER_STAGE_FRAGMENT_BIT);

    VkPipelineVertexInputStateCreateInfo vertex_input{
        VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    VkPipelineInputAssemblyStateCreateInfo assembly{
        VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo viewport{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    viewport.viewportCount = 1;
    viewport.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo raster{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    raster.polygonMode = VK_POLYGON_MODE_FILL;
    raster.cullMode = VK_CULL_MODE_NONE;
    raster.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo multisample{
        VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    multisample.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineColorBlendStateCreateInfo blend{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    const VkDynamicState dynamic_states[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamic_states;

    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.renderPass = ctx.attachmentless_pass();
    info.stageCount = std::uint32_t(stages.size());
    info.pStages = stages.data();
    info.pVertexInputState = &vertex_input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewport;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pColorBlendState = &blend;
    info.pDynamicState = &dynamic;
    info.layout = p.layout_;
    if (status) {
        VkResult r = ctx.vk().vkCreateGraphicsPipelines(ctx.device(), ctx.pipeline_cache(), 1, &info,
                                                        ctx.allocator(), &p.pipeline_);
        if (r != VK_SUCCESS)
            status = Status::failure(std::string("vkCreateGraphicsPipelines failed: ") + to_string(r));
        else
            ctx.name(VK_OBJECT_TYPE_PIPELINE, std::uint64_t(p.pipeline_), name);
    }
    for (VkShaderModule m : modules)
        ctx.vk().vkDestroyShaderModule(ctx.device(), m, ctx.allocator());
    if (!status) return status;
    return p;
}

void Pipeline::bind(VkCommandBuffer cmd, const void* push, std::uint32_t bytes) const {
    ctx_->vk().vkCmdBindPipeline(cmd, bind_point_, pipeline_);
    if (bytes) ctx_->vk().vkCmdPushConstants(cmd, layout_, VK_SHADER_STAGE_ALL, 0, bytes, push);
}

template <class Record> void Pipeline::timed(VkCommandBuffer cmd, Record record) const {
    Profiler* profiler = ctx_->dispatch_profiler();
    if (profiler) profiler->begin(cmd, name_);
    record();
    if (profiler) profiler->end(cmd);
    ctx_->count_dispatch();
}

void Pipeline::dispatch(VkCommandBuffer cmd, std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
    timed(cmd, [&] { ctx_->vk().vkCmdDispatch(cmd, x, y, z); });
}

void Pipeline::dispatch_indirect(VkCommandBuffer cmd, VkBuffer arguments, VkDeviceSize offset) const {
    timed(cmd, [&] { ctx_->vk().vkCmdDispatchIndirect(cmd, arguments, offset); });
}

void Pipeline::draw(VkCommandBuffer cmd, std::uint32_t vertices) const {
    timed(cmd, [&] { ctx_->vk().vkCmdDraw(cmd, vertices, 1, 0, 0); });
}

void Pipeline::release() {
    if (!ctx_) return;
    if (pipeline_) ctx_->vk().vkDestroyPipeline(ctx_->device(), pipeline_, ctx_->allocator());
    if (layout_) ctx_->vk().vkDestroyPipelineLayout(ctx_->device(), layout_, ctx_->allocator());
    pipeline_ = VK_NULL_HANDLE;
    layout_ = VK_NULL_HANDLE;
}

Pipeline::~Pipeline() {
    release();
}

Pipeline::Pipeline(Pipeline&& other) noexcept {
    *this = std::move(other);
}

Pipeline& Pipeline::operator=(Pipeline&& other) noexcept {
    if (this != &other) {
        release();
        ctx_ = std::exchange(other.ctx_, nullptr);
        pipeline_ = std::exchange(other.pipeline_, VK_NULL_HANDLE);
        layout_ = std::exchange(other.layout_, VK_NULL_HANDLE);
        bind_point_ = other.bind_point_;
        name_ = other.name_;
    }
    return *this;
}

} // namespace gust::gpu
