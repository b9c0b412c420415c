#include "renderer.hpp"

#include "sample/sample_io.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <gust_shaders/arrows_vert.h>
#include <gust_shaders/foliage_comp.h>
#include <gust_shaders/grass_frag.h>
#include <gust_shaders/grass_vert.h>
#include <gust_shaders/lines_frag.h>
#include <gust_shaders/lines_vert.h>
#include <gust_shaders/mesh_frag.h>
#include <gust_shaders/mesh_vert.h>
#include <gust_shaders/slice_comp.h>
#include <gust_shaders/slice_frag.h>
#include <gust_shaders/slice_vert.h>
#include <gust_shaders/voxels_frag.h>
#include <gust_shaders/voxels_vert.h>
#include <stdexcept>

namespace sample {

namespace io = gust::shaderio;

namespace {

constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
/// Foliage bend per (m/s)^2 of wind: a blade in a steady 4 m/s leans its tip over by 40% of its height.
constexpr float kFoliageDrag = 0.025f;

static_assert(sizeof(io::DrawPush) == 96);
static_assert(sizeof(io::FrameUniforms) == (2 + io::kWindCascades) * 64 + 8 * 16);
static_assert(sizeof(io::VoxelFace) == 8);
static_assert(sizeof(io::FoliageSeed) == 32 && sizeof(io::FoliageState) == 16);
/// The descriptor set's bindings (sample_common.glsl, slice.comp, slice.frag).
constexpr std::uint32_t kBindings = 7;

template <std::size_t N> std::span<const std::uint32_t> spirv(const std::uint32_t (&code)[N]) {
    return code;
}

} // namespace

Renderer::Renderer(VulkanHost& vk, const World& world, VkFormat colour_format, VkImageLayout final_layout)
    : vk_(vk) {
    VkDevice device = vk_.device();
    VkAttachmentDescription attachments[2]{};
    attachments[0].format = colour_format;
    attachments[0].samples = VK_SAMPLE_COUNT_1_BIT;
    attachments[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    attachments[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    attachments[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    attachments[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    attachments[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    attachments[0].finalLayout = final_layout;
    attachments[1] = attachments[0];
    attachments[1].format = kDepthFormat;
    attachments[1].storeOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    attachments[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    VkAttachmentReference colour_ref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
    VkAttachmentReference depth_ref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription subpass{};
    subpass.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    subpass.colorAttachmentCount = 1;
    subpass.pColorAttachments = &colour_ref;
    subpass.pDepthStencilAttachment = &depth_ref;
    // The colour target may still be read by the presentation engine or the last frame's copy, and the
    // depth buffer by the last frame's tests: wait for both before clearing.
    VkSubpassDependency dependency{};
    dependency.srcSubpass = VK_SUBPASS_EXTERNAL;
    dependency.dstSubpass = 0;
    dependency.srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT |
                              VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
    dependency.dstStageMask =
        VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT;
    dependency.srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_TRANSFER_READ_BIT;
    dependency.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT |
                               VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                               VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
    VkRenderPassCreateInfo pass{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    pass.attachmentCount = 2;
    pass.pAttachments = attachments;
    pass.subpassCount = 1;
    pass.pSubpasses = &subpass;
    pass.dependencyCount = 1;
    pass.pDependencies = &dependency;
    check(vkCreateRenderPass(device, &pass, nullptr, &pass_), "vkCreateRenderPass");

    const VkShaderStageFlags all =
        VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
    VkDescriptorSetLayoutBinding bindings[kBindings] = {
        {0, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1, all, nullptr},
        {1, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, io::kWindCascades, all, nullptr},
        {2, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {3, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {4, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, all, nullptr},
        {5, VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1, all, nullptr},
        {6, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, all, nullptr},
    };
    VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
    set_info.bindingCount = kBindings;
    set_info.pBindings = bindings;
    check(vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout_),
          "vkCreateDescriptorSetLayout");
    VkDescriptorPoolSize sizes[4] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                     {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, io::kWindCascades + 1},
                                     {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 3},
                                     {VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, 1}};
    VkDescriptorPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool_info.maxSets = 1;
    pool_info.poolSizeCount = 4;
    pool_info.pPoolSizes = sizes;
    check(vkCreateDescriptorPool(device, &pool_info, nullptr, &pool_), "vkCreateDescriptorPool");
    VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    alloc.descriptorPool = pool_;
    alloc.descriptorSetCount = 1;
    alloc.pSetLayouts = &set_layout_;
    check(vkAllocateDescriptorSets(device, &alloc, &set_), "vkAllocateDescriptorSets");
    VkPushConstantRange push{all, 0, sizeof(io::DrawPush)};
    VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
    layout_info.setLayoutCount = 1;
    layout_info.pSetLayouts = &set_layout_;
    layout_info.pushConstantRangeCount = 1;
    layout_info.pPushConstantRanges = &push;
    check(vkCreatePipelineLayout(device, &layout_info, nullptr, &layout_), "vkCreatePipelineLayout");

    VkShaderModule mesh_v = vk_.create_shader(spirv(mesh_vert)), mesh_f = vk_.create_shader(spirv(mesh_frag));
    VkShaderModule grass_v = vk_.create_shader(spirv(grass_vert)),
                   grass_f = vk_.create_shader(spirv(grass_frag));
    VkShaderModule voxels_v = vk_.create_shader(spirv(voxels_vert)),
                   voxels_f = vk_.create_shader(spirv(voxels_frag));
    VkShaderModule lines_v = vk_.create_shader(spirv(lines_vert)),
                   lines_f = vk_.create_shader(spirv(lines_frag));
    VkShaderModule arrows_v = vk_.create_shader(spirv(arrows_vert));
    VkShaderModule slice_v = vk_.create_shader(spirv(slice_vert)),
                   slice_f = vk_.create_shader(spirv(slice_frag));
    VkShaderModule foliage = vk_.create_shader(spirv(foliage_comp)),
                   slice_fill = vk_.create_shader(spirv(slice_comp));
    mesh_ = graphics(mesh_v, mesh_f, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST, true, false, true, false);
    grass_ = graphics(grass_v, grass_f, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST, false, false, true, false);
    voxels_ = graphics(voxels_v, voxels_f, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST, false, false, true, false);
    lines_ = graphics(lines_v, lines_f, VK_PRIMITIVE_TOPOLOGY_LINE_LIST, false, true, false, false);
    arrows_ = graphics(arrows_v, lines_f, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST, false, false, false, false);
    slice_ = graphics(slice_v, slice_f, VK_PRIMITIVE_TOPOLOGY_TRIANGLE_STRIP, false, false, false, true);
    foliage_ = compute(foliage);
    slice_fill_ = compute(slice_fill);
    for (VkShaderModule m : {mesh_v, mesh_f, grass_v, grass_f, voxels_v, voxels_f, lines_v, lines_f, arrows_v,
                             slice_v, slice_f, foliage, slice_fill})
        vkDestroyShaderModule(device, m, nullptr);
    VkSamplerCreateInfo sampler{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    sampler.magFilter = sampler.minFilter = VK_FILTER_LINEAR;
    sampler.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    sampler.addressModeU = sampler.addressModeV = sampler.addressModeW =
        VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    check(vkCreateSampler(device, &sampler, nullptr, &slice_sampler_), "vkCreateSampler");

    uniforms_ = vk_.create_buffer(sizeof(io::FrameUniforms), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, true);
    const std::vector<FoliageSeed>& seeds = world.foliage();
    foliage_count_ = static_cast<std::uint32_t>(seeds.size());
    grass_count_ = world.grass_count();
    seeds_ = vk_.create_buffer(std::max<std::size_t>(seeds.size(), 1) * sizeof(FoliageSeed),
                               VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
    std::memcpy(seeds_.mapped, seeds.data(), seeds.size() * sizeof(FoliageSeed));
    // The state is host-visible so that stats can report how far the grass bends.
    states_ = vk_.create_buffer(std::max<std::size_t>(seeds.size(), 1) * sizeof(io::FoliageState),
                                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
    std::memset(states_.mapped, 0, states_.size);

    for (const WorldMesh& m : world.meshes()) {
        MeshBuffers buffers;
        buffers.vertices = vk_.create_buffer(m.mesh.positions.size() * sizeof(glm::vec3),
                                             VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, true);
        std::memcpy(buffers.vertices.mapped, m.mesh.positions.data(), buffers.vertices.size);
        buffers.indices = vk_.create_buffer(m.mesh.indices.size() * sizeof(std::uint32_t),
                                            VK_BUFFER_USAGE_INDEX_BUFFER_BIT, true);
        std::memcpy(buffers.indices.mapped, m.mesh.indices.data(), buffers.indices.size);
        buffers.index_count = static_cast<std::uint32_t>(m.mesh.indices.size());
        meshes_.push_back(buffers);
    }

    // Until the first voxels arrive the face list is empty, but bound, so the set is always complete.
    faces_ = vk_.create_buffer(4096, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
    update_world(world);
}

Renderer::~Renderer() {
    VkDevice device = vk_.device();
    vkDeviceWaitIdle(device);
    forget_targets();
    for (MeshBuffers& m : meshes_) {
        vk_.destroy(m.vertices);
        vk_.destroy(m.indices);
    }
    for (Buffer* b : {&uniforms_, &seeds_, &states_, &lines_buffer_, &faces_})
        vk_.destroy(*b);
    vk_.destroy(slice_image_);
    vkDestroySampler(device, slice_sampler_, nullptr);
    for (VkPipeline p : {mesh_, grass_, voxels_, lines_, arrows_, slice_, foliage_, slice_fill_})
        vkDestroyPipeline(device, p, nullptr);
    vkDestroyPipelineLayout(device, layout_, nullptr);
    vkDestroyDescriptorPool(device, pool_, nullptr);
    vkDestroyDescriptorSetLayout(device, set_layout_, nullptr);
    vkDestroyRenderPass(device, pass_, nullptr);
}

VkPipeline Renderer::compute(VkShaderModule shader) {
    VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    info.stage.module = shader;
    info.stage.pName = "main";
    info.layout = layout_;
    VkPipeline pipeline = VK_NULL_HANDLE;
    check(vkCreateComputePipelines(vk_.device(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
          "vkCreateComputePipelines");
    return pipeline;
}

VkPipeline Renderer::graphics(VkShaderModule vert, VkShaderModule frag, VkPrimitiveTopology topology,
                              bool mesh_input, bool line_input, bool depth_write, bool blend) {
    VkPipelineShaderStageCreateInfo stages[2]{};
    stages[0] = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vert;
    stages[0].pName = "main";
    stages[1] = stages[0];
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = frag;
    VkVertexInputBindingDescription binding{0, 0, VK_VERTEX_INPUT_RATE_VERTEX};
    VkVertexInputAttributeDescription attributes[2] = {{0, 0, VK_FORMAT_R32G32B32_SFLOAT, 0},
                                                       {1, 0, VK_FORMAT_R32G32B32A32_SFLOAT, 12}};
    VkPipelineVertexInputStateCreateInfo input{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    if (mesh_input || line_input) {
        binding.stride = mesh_input ? sizeof(glm::vec3) : sizeof(LineVertex);
        input.vertexBindingDescriptionCount = 1;
        input.pVertexBindingDescriptions = &binding;
        input.vertexAttributeDescriptionCount = mesh_input ? 1 : 2;
        input.pVertexAttributeDescriptions = attributes;
    }
    VkPipelineInputAssemblyStateCreateInfo assembly{
        VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    assembly.topology = topology;
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
    VkPipelineDepthStencilStateCreateInfo depth{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    depth.depthTestEnable = VK_TRUE;
    depth.depthWriteEnable = depth_write ? VK_TRUE : VK_FALSE;
    depth.depthCompareOp = VK_COMPARE_OP_LESS_OR_EQUAL;
    VkPipelineColorBlendAttachmentState attachment{};
    attachment.colorWriteMask = VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                                VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT;
    if (blend) {
        attachment.blendEnable = VK_TRUE;
        attachment.srcColorBlendFactor = VK_BLEND_FACTOR_SRC_ALPHA;
        attachment.dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
        attachment.colorBlendOp = VK_BLEND_OP_ADD;
        attachment.srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
        attachment.dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
        attachment.alphaBlendOp = VK_BLEND_OP_ADD;
    }
    VkPipelineColorBlendStateCreateInfo colour{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    colour.attachmentCount = 1;
    colour.pAttachments = &attachment;
    const VkDynamicState dynamic_states[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR};
    VkPipelineDynamicStateCreateInfo dynamic{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dynamic.dynamicStateCount = 2;
    dynamic.pDynamicStates = dynamic_states;
    VkGraphicsPipelineCreateInfo info{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO};
    info.stageCount = 2;
    info.pStages = stages;
    info.pVertexInputState = &input;
    info.pInputAssemblyState = &assembly;
    info.pViewportState = &viewport;
    info.pRasterizationState = &raster;
    info.pMultisampleState = &multisample;
    info.pDepthStencilState = &depth;
    info.pColorBlendState = &colour;
    info.pDynamicState = &dynamic;
    info.layout = layout_;
    info.renderPass = pass_;
    VkPipeline pipeline = VK_NULL_HANDLE;
    check(vkCreateGraphicsPipelines(vk_.device(), VK_NULL_HANDLE, 1, &info, nullptr, &pipeline),
          "vkCreateGraphicsPipelines");
    return pipeline;
}

void Renderer::write_descriptors() {
    VkDescriptorBufferInfo uniforms{uniforms_.buffer, 0, VK_WHOLE_SIZE};
    VkDescriptorBufferInfo seeds{seeds_.buffer, 0, VK_WHOLE_SIZE};
    VkDescriptorBufferInfo states{states_.buffer, 0, VK_WHOLE_SIZE};
    // The slots past the coarsest cascade hold the coarsest again (sample_io.h, kWindCascades).
    VkDescriptorImageInfo wind[io::kWindCascades];
    for (std::uint32_t k = 0; k < io::kWindCascades; ++k) {
        const gust::WindTexture& t = wind_[std::min<std::size_t>(k, wind_.size() - 1)];
        wind[k] = {t.sampler, t.view, t.layout};
    }
    VkDescriptorBufferInfo faces{faces_.buffer, 0, VK_WHOLE_SIZE};
    VkDescriptorImageInfo slice_out{VK_NULL_HANDLE, slice_image_.view, VK_IMAGE_LAYOUT_GENERAL};
    VkDescriptorImageInfo slice_in{slice_sampler_, slice_image_.view, VK_IMAGE_LAYOUT_GENERAL};
    VkWriteDescriptorSet writes[kBindings]{};
    for (std::uint32_t i = 0; i < kBindings; ++i) {
        writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[i].dstSet = set_;
        writes[i].dstBinding = i;
        writes[i].descriptorCount = 1;
    }
    writes[0].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
    writes[0].pBufferInfo = &uniforms;
    writes[1].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[1].descriptorCount = io::kWindCascades;
    writes[1].pImageInfo = wind;
    writes[2].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[2].pBufferInfo = &seeds;
    writes[3].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[3].pBufferInfo = &states;
    writes[4].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[4].pBufferInfo = &faces;
    writes[5].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_IMAGE;
    writes[5].pImageInfo = &slice_out;
    writes[6].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    writes[6].pImageInfo = &slice_in;
    vkUpdateDescriptorSets(vk_.device(), kBindings, writes, 0, nullptr);
}

void Renderer::set_wind(std::span<const gust::WindTexture> textures, const gust::WindDomain& domain) {
    if (textures.empty() || textures.size() > io::kWindCascades)
        throw std::runtime_error("the sample's shaders read 1 to 4 wind cascades");
    wind_ = textures;
    domain_ = domain;
    // The slice's texels tile the coarsest cascade, each the finest cell or, where that would pass
    // kSliceTexelsMax along a side, a power of two of them (which divides the coarsest cell, so the
    // texels still tile it exactly).
    const std::uint32_t finest_per_coarsest = static_cast<std::uint32_t>(
        std::lround(std::pow(static_cast<float>(domain.ratio), static_cast<float>(textures.size() - 1))));
    std::uint32_t finest_per_texel = 1;
    while (std::max(domain.cells[0], domain.cells[2]) * finest_per_coarsest / finest_per_texel >
           io::kSliceTexelsMax)
        finest_per_texel *= 2;
    vk_.destroy(slice_image_);
    slice_image_ =
        vk_.create_image(VK_FORMAT_R16G16B16A16_SFLOAT,
                         {domain.cells[0] * finest_per_coarsest / finest_per_texel,
                          domain.cells[2] * finest_per_coarsest / finest_per_texel, 1},
                         VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_COLOR_BIT);
    // GENERAL for good: slice.comp writes it and slice.frag samples it every frame the slice shows.
    vk_.submit_now([&](VkCommandBuffer cmd) {
        transition(cmd, slice_image_.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                   VK_IMAGE_LAYOUT_GENERAL, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, 0,
                   VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_ACCESS_SHADER_WRITE_BIT);
    });
    write_descriptors();
}

void Renderer::set_voxels(const gust::VoxelGridInfo& grid, std::span<const gust::VoxelCoord> voxels) {
    face_finder_.find(voxels, face_list_);
    const VkDeviceSize bytes = face_list_.size() * sizeof(VoxelFace);
    if (bytes > faces_.size) {
        // The last frame's draw may still read the old list, and the descriptor set names it.
        vkDeviceWaitIdle(vk_.device());
        vk_.destroy(faces_);
        faces_ = vk_.create_buffer(bytes + bytes / 2, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, true);
        write_descriptors();
    }
    if (bytes > 0) std::memcpy(faces_.mapped, face_list_.data(), bytes);
    face_count_ = static_cast<std::uint32_t>(face_list_.size());
    voxel_grid_ = grid;
}

void Renderer::set_lines(std::span<const LineVertex> lines) {
    if (lines.size_bytes() > lines_buffer_.size) {
        vkDeviceWaitIdle(vk_.device());
        vk_.destroy(lines_buffer_);
        lines_buffer_ = vk_.create_buffer(std::max<VkDeviceSize>(lines.size_bytes() * 2, 4096),
                                          VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, true);
    }
    if (!lines.empty()) std::memcpy(lines_buffer_.mapped, lines.data(), lines.size_bytes());
    line_count_ = static_cast<std::uint32_t>(lines.size());
}

void Renderer::update_world(const World& world) {
    draws_.clear();
    for (const WorldObject& o : world.objects()) {
        if (o.kind == ObjectKind::Skinned) {
            const std::vector<glm::vec3>& posed = world.posed(o.mesh);
            std::memcpy(
                meshes_[o.mesh].vertices.mapped, posed.data(),
                std::min<std::size_t>(posed.size() * sizeof(glm::vec3), meshes_[o.mesh].vertices.size));
        }
        const float slot = o.kind == ObjectKind::Tree ? static_cast<float>(o.foliage_slot) : -1.0f;
        // Q hides what gust voxelizes (the ground stays, so the voxels have a floor to stand on).
        const bool solid = o.kind == ObjectKind::Rigid || o.kind == ObjectKind::Skinned ||
                           (o.kind == ObjectKind::Static && o.name != "ground");
        draws_.push_back({o.mesh, solid, o.model, glm::vec4(o.color, 1.0f),
                          glm::vec4(slot, o.sway_height, o.sway_length, 0.0f)});
    }
}

VkFramebuffer Renderer::framebuffer(VkImageView target, VkExtent2D extent) {
    if (depth_extent_.width != extent.width || depth_extent_.height != extent.height) {
        forget_targets();
        depth_ = vk_.create_image(kDepthFormat, {extent.width, extent.height, 1},
                                  VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, VK_IMAGE_ASPECT_DEPTH_BIT);
        depth_extent_ = extent;
    }
    if (auto found = framebuffers_.find(target); found != framebuffers_.end()) return found->second;
    VkImageView views[2] = {target, depth_.view};
    VkFramebufferCreateInfo info{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
    info.renderPass = pass_;
    info.attachmentCount = 2;
    info.pAttachments = views;
    info.width = extent.width;
    info.height = extent.height;
    info.layers = 1;
    VkFramebuffer fb = VK_NULL_HANDLE;
    check(vkCreateFramebuffer(vk_.device(), &info, nullptr, &fb), "vkCreateFramebuffer");
    framebuffers_[target] = fb;
    return fb;
}

void Renderer::forget_targets() {
    for (auto& [view, fb] : framebuffers_)
        vkDestroyFramebuffer(vk_.device(), fb, nullptr);
    framebuffers_.clear();
    vk_.destroy(depth_);
    depth_extent_ = {};
}

std::pair<float, float> Renderer::grass_bend() const {
    const auto* states = static_cast<const io::FoliageState*>(states_.mapped);
    double sum = 0.0;
    float largest = 0.0f;
    for (std::uint32_t i = 0; i < grass_count_; ++i) {
        const float bend = glm::length(glm::vec2(states[i].bend));
        sum += bend;
        largest = std::max(largest, bend);
    }
    return {grass_count_ ? static_cast<float>(sum / grass_count_) : 0.0f, largest};
}

float Renderer::crown_bend(std::span<const std::uint32_t> slots) const {
    const auto* states = static_cast<const io::FoliageState*>(states_.mapped);
    float sum = 0.0f;
    for (std::uint32_t slot : slots)
        sum += glm::length(glm::vec2(states[slot].bend));
    return slots.empty() ? 0.0f : sum / static_cast<float>(slots.size());
}

void Renderer::begin(VkCommandBuffer cmd, VkImageView target, VkExtent2D extent, const FrameView& view,
                     const Views& views) {
    io::FrameUniforms u{};
    u.view_proj = view.view_proj;
    u.inverse_view_proj = glm::inverse(view.view_proj);
    // Each cascade's grid scrolls with the focus: its world_to_texture as of gust's last step.
    for (std::uint32_t k = 0; k < io::kWindCascades; ++k)
        std::memcpy(&u.wind_world_to_texture[k],
                    wind_[std::min<std::size_t>(k, wind_.size() - 1)].world_to_texture.m, sizeof(glm::mat4));
    u.ambient = glm::vec4(view.ambient, 0.0f);
    const glm::vec3 coarse_min = glm::vec3(glm::inverse(u.wind_world_to_texture[wind_.size() - 1]) *
                                           glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    u.coarse_min = glm::vec4(coarse_min, domain_.cell_size * std::pow(static_cast<float>(domain_.ratio),
                                                                      static_cast<float>(wind_.size() - 1)));
    u.camera = glm::vec4(view.eye, view.time);
    u.light = glm::vec4(glm::normalize(glm::vec3(0.45f, 0.8f, 0.3f)), static_cast<float>(grass_count_));
    u.voxel_origin =
        glm::vec4(voxel_grid_.origin.x, voxel_grid_.origin.y, voxel_grid_.origin.z, voxel_grid_.voxel_size);
    u.wind_min = glm::vec4(view.wind_origin, domain_.cell_size);
    u.wind_cells = glm::vec4(static_cast<float>(domain_.cells[0]), static_cast<float>(domain_.cells[1]),
                             static_cast<float>(domain_.cells[2]), 8.0f);
    // Arrows as long as 0.15 of a cell per m/s, so that they keep clear of each other on any grid.
    u.slice = glm::vec4(views.slice_height, 0.15f * domain_.cell_size, static_cast<float>(extent.width),
                        static_cast<float>(extent.height));
    std::memcpy(uniforms_.mapped, &u, sizeof(u));

    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, layout_, 0, 1, &set_, 0, nullptr);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, layout_, 0, 1, &set_, 0, nullptr);
    bool computed = false;
    if (view.dt > 0.0f && foliage_count_ > 0) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, foliage_);
        const io::FoliagePush push{view.dt, foliage_count_, kFoliageDrag, 0.0f};
        vkCmdPushConstants(cmd, layout_,
                           VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT |
                               VK_SHADER_STAGE_COMPUTE_BIT,
                           0, sizeof(push), &push);
        vkCmdDispatch(cmd, (foliage_count_ + io::kFoliageGroupSize - 1) / io::kFoliageGroupSize, 1, 1);
        computed = true;
    }
    if (views.slice) {
        // Every cascade's blend once per texel here, rather than once per fragment in slice.frag.
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, slice_fill_);
        vkCmdDispatch(cmd, (slice_image_.extent.width + io::kSliceGroupSize - 1) / io::kSliceGroupSize,
                      (slice_image_.extent.height + io::kSliceGroupSize - 1) / io::kSliceGroupSize, 1);
        computed = true;
    }
    if (computed) {
        VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
        vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT,
                             VK_PIPELINE_STAGE_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_FRAGMENT_SHADER_BIT, 0,
                             1, &barrier, 0, nullptr, 0, nullptr);
    }

    VkClearValue clears[2]{};
    clears[0].color = {{0.62f, 0.72f, 0.85f, 1.0f}};
    clears[1].depthStencil = {1.0f, 0};
    VkRenderPassBeginInfo begin{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
    begin.renderPass = pass_;
    begin.framebuffer = framebuffer(target, extent);
    begin.renderArea = {{0, 0}, extent};
    begin.clearValueCount = 2;
    begin.pClearValues = clears;
    vkCmdBeginRenderPass(cmd, &begin, VK_SUBPASS_CONTENTS_INLINE);
    VkViewport viewport{0.0f, 0.0f, static_cast<float>(extent.width), static_cast<float>(extent.height),
                        0.0f, 1.0f};
    VkRect2D scissor{{0, 0}, extent};
    vkCmdSetViewport(cmd, 0, 1, &viewport);
    vkCmdSetScissor(cmd, 0, 1, &scissor);

    const VkShaderStageFlags all =
        VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT | VK_SHADER_STAGE_COMPUTE_BIT;
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, mesh_);
    for (const Draw& d : draws_) {
        if (d.solid && !views.triangles) continue;
        io::DrawPush push{d.model, d.colour, d.sway};
        vkCmdPushConstants(cmd, layout_, all, 0, sizeof(push), &push);
        const VkDeviceSize offset = 0;
        vkCmdBindVertexBuffers(cmd, 0, 1, &meshes_[d.mesh].vertices.buffer, &offset);
        vkCmdBindIndexBuffer(cmd, meshes_[d.mesh].indices.buffer, 0, VK_INDEX_TYPE_UINT32);
        vkCmdDrawIndexed(cmd, meshes_[d.mesh].index_count, 1, 0, 0, 0);
    }
    if (views.grass && grass_count_ > 0) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, grass_);
        vkCmdDraw(cmd, grass_count_ * io::kBladeVertices, 1, 0, 0);
    }
    if (views.voxels && face_count_ > 0) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, voxels_);
        vkCmdDraw(cmd, face_count_ * io::kFaceVertices, 1, 0, 0);
    }
    if ((views.nodes || views.cascades) && line_count_ > 0) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, lines_);
        const VkDeviceSize offset = 0;
        vkCmdBindVertexBuffers(cmd, 0, 1, &lines_buffer_.buffer, &offset);
        vkCmdDraw(cmd, line_count_, 1, 0, 0);
    }
    if (views.arrows) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, arrows_);
        vkCmdDraw(cmd, io::kArrowVertices, domain_.cells[0] * domain_.cells[2], 0, 0);
    }
    if (views.slice) {
        vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, slice_);
        vkCmdDraw(cmd, 4, 1, 0, 0);
    }
}

} // namespace sample
