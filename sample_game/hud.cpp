#include "hud.hpp"

#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_vulkan.h>
#include <imgui.h>

namespace sample {

namespace {
void check_imgui(VkResult result) {
    check(result, "Dear ImGui's Vulkan backend");
}
} // namespace

Hud::Hud(VulkanHost& vk, VkRenderPass pass, std::uint32_t image_count, GLFWwindow* window, VkExtent2D extent)
    : vk_(vk), window_(window), extent_(extent) {
    VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 4};
    VkDescriptorPoolCreateInfo pool{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
    pool.flags = VK_DESCRIPTOR_POOL_CREATE_FREE_DESCRIPTOR_SET_BIT;
    pool.maxSets = 4;
    pool.poolSizeCount = 1;
    pool.pPoolSizes = &size;
    check(vkCreateDescriptorPool(vk_.device(), &pool, nullptr, &pool_), "vkCreateDescriptorPool");

    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    // No imgui.ini next to wherever the game was started from.
    io.IniFilename = nullptr;
    ImGui::StyleColorsDark();
    ImGui::GetStyle().Alpha = 0.92f;
    if (window_) ImGui_ImplGlfw_InitForVulkan(window_, true);
    ImGui_ImplVulkan_InitInfo info{};
    info.Instance = vk_.instance();
    info.PhysicalDevice = vk_.physical_device();
    info.Device = vk_.device();
    info.QueueFamily = vk_.queue_family();
    info.Queue = vk_.queue();
    info.DescriptorPool = pool_;
    info.MinImageCount = std::max(image_count, 2u);
    info.ImageCount = std::max(image_count, 2u);
    info.MSAASamples = VK_SAMPLE_COUNT_1_BIT;
    info.CheckVkResultFn = check_imgui;
    ImGui_ImplVulkan_Init(&info, pass);
    vk_.submit_now([](VkCommandBuffer cmd) { ImGui_ImplVulkan_CreateFontsTexture(cmd); });
    ImGui_ImplVulkan_DestroyFontUploadObjects();
}

Hud::~Hud() {
    vkDeviceWaitIdle(vk_.device());
    ImGui_ImplVulkan_Shutdown();
    if (window_) ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
    vkDestroyDescriptorPool(vk_.device(), pool_, nullptr);
}

void Hud::begin_frame(float dt) {
    ImGui_ImplVulkan_NewFrame();
    if (window_) {
        ImGui_ImplGlfw_NewFrame();
    } else {
        ImGuiIO& io = ImGui::GetIO();
        io.DisplaySize = ImVec2(static_cast<float>(extent_.width), static_cast<float>(extent_.height));
        io.DeltaTime = dt > 0.0f ? dt : 1.0f / 30.0f;
    }
    ImGui::NewFrame();
}

void Hud::draw(VkCommandBuffer cmd) {
    ImGui::Render();
    ImGui_ImplVulkan_RenderDrawData(ImGui::GetDrawData(), cmd);
}

bool Hud::wants_mouse() const {
    return ImGui::GetIO().WantCaptureMouse;
}
bool Hud::wants_keyboard() const {
    return ImGui::GetIO().WantCaptureKeyboard;
}

} // namespace sample
