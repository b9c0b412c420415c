#include "game.hpp"

#include "display.hpp"
#include "hud.hpp"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <imgui.h>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <tuple>

namespace sample {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// Orbit camera (drag to turn, wheel to zoom) around the middle of the field or, following, the fox.
struct Camera {
    float yaw = 2.4f, pitch = 0.38f, distance = 19.0f;
    glm::vec3 target{0.0f, 1.0f, 0.0f};
    bool follow = false;

    glm::vec3 eye() const {
        return target + distance * glm::vec3(std::cos(pitch) * std::cos(yaw), std::sin(pitch),
                                             std::cos(pitch) * std::sin(yaw));
    }
    glm::mat4 view_proj(float aspect) const {
        glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(55.0f), aspect, 0.1f, 300.0f);
        proj[1][1] *= -1.0f; // Vulkan's clip space has y down
        return proj * glm::lookAt(eye(), target, glm::vec3(0, 1, 0));
    }
};

/// Where gust's domain is centred for a focus on the ground at `focus`: the domain's floor sits 1 m under
/// the ground so that the ground is a solid inside it.
gust::Vec3 domain_centre(glm::vec3 focus, float cell_size, std::uint32_t cells_y) {
    return {focus.x, 0.5f * cell_size * static_cast<float>(cells_y) - 1.0f, focus.z};
}

/// Key of a tree node for telling this frame's nodes from last frame's.
using NodeKey = std::tuple<std::uint32_t, std::int64_t, std::int64_t, std::int64_t>;

/// Twelve edges of a box as line vertices.
void add_box(std::vector<LineVertex>& out, glm::vec3 lo, float size, glm::vec4 colour) {
    const glm::vec3 hi = lo + size;
    const glm::vec3 c[8] = {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z},
                            {lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}};
    const int edges[12][2] = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                              {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
    for (const auto& e : edges) {
        out.push_back({c[e[0]], colour});
        out.push_back({c[e[1]], colour});
    }
}

class Game {
  public:
    explicit Game(const GameOptions& options) : options_(options) {}
    ~Game() {
        hud_.reset();
        offscreen_.reset();
        swapchain_.reset();
        renderer_.reset();
        wind_.reset();
        if (vk_) {
            vkDeviceWaitIdle(vk_->device());
            if (fence_) vkDestroyFence(vk_->device(), fence_, nullptr);
        }
        vk_.reset();
        if (window_) glfwDestroyWindow(window_);
        if (glfw_) glfwTerminate();
    }

    int run();

  private:
    bool open_window();
    void make_wind();
    void on_key(int key);
    void build_hud(double frame_ms);
    void refresh_debug_views();
    void write_stats(std::ofstream& stats, std::uint64_t frame, double t, double frame_ms, double wind_ms);

    GameOptions options_;
    bool glfw_ = false;
    GLFWwindow* window_ = nullptr;
    std::unique_ptr<VulkanHost> vk_;
    std::unique_ptr<World> world_;
    std::unique_ptr<gust::System> wind_;
    gust::WindDomain domain_;
    std::unique_ptr<Renderer> renderer_;
    std::unique_ptr<Swapchain> swapchain_;
    std::unique_ptr<Offscreen> offscreen_;
    std::unique_ptr<Hud> hud_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    Camera camera_;
    Views views_;
    bool paused_ = false, show_hud_ = true, rebuild_wind_ = false;
    double fps_ = 0.0;
    std::set<NodeKey> last_nodes_;
    std::map<std::uint32_t, std::uint64_t> nodes_per_level_;
    bool dragging_ = false;
    double drag_x_ = 0.0, drag_y_ = 0.0;
};

bool Game::open_window() {
    if (options_.headless) return false;
    const char* x11 = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!x11 || !*x11) && (!wayland || !*wayland)) {
        std::fprintf(stderr, "gust_sample: no display; running headless\n");
        return false;
    }
    glfw_ = glfwInit() == GLFW_TRUE;
    if (!glfw_ || !glfwVulkanSupported()) {
        std::fprintf(stderr, "gust_sample: GLFW cannot open a Vulkan window here; running headless\n");
        return false;
    }
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    window_ = glfwCreateWindow(static_cast<int>(options_.width), static_cast<int>(options_.height),
                               "gust sample: wind through grass", nullptr, nullptr);
    if (!window_) {
        std::fprintf(stderr, "gust_sample: cannot create a window; running headless\n");
        return false;
    }
    glfwSetWindowUserPointer(window_, this);
    // Set before ImGui's, which chain to these.
    glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int) {
        auto* game = static_cast<Game*>(glfwGetWindowUserPointer(w));
        if (action == GLFW_PRESS && !(game->hud_ && game->hud_->wants_keyboard())) game->on_key(key);
    });
    glfwSetMouseButtonCallback(window_, [](GLFWwindow* w, int button, int action, int) {
        auto* game = static_cast<Game*>(glfwGetWindowUserPointer(w));
        if (button != GLFW_MOUSE_BUTTON_LEFT) return;
        game->dragging_ = action == GLFW_PRESS && !(game->hud_ && game->hud_->wants_mouse());
        glfwGetCursorPos(w, &game->drag_x_, &game->drag_y_);
    });
    glfwSetCursorPosCallback(window_, [](GLFWwindow* w, double x, double y) {
        auto* game = static_cast<Game*>(glfwGetWindowUserPointer(w));
        if (!game->dragging_) return;
        game->camera_.yaw += 0.008f * static_cast<float>(x - game->drag_x_);
        game->camera_.pitch =
            std::clamp(game->camera_.pitch + 0.008f * static_cast<float>(y - game->drag_y_), 0.05f, 1.5f);
        game->drag_x_ = x;
        game->drag_y_ = y;
    });
    glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double dy) {
        auto* game = static_cast<Game*>(glfwGetWindowUserPointer(w));
        if (game->hud_ && game->hud_->wants_mouse()) return;
        game->camera_.distance =
            std::clamp(game->camera_.distance * std::pow(0.9f, static_cast<float>(dy)), 2.0f, 120.0f);
    });
    return true;
}

void Game::on_key(int key) {
    switch (key) {
    case GLFW_KEY_Q:
        views_.triangles = !views_.triangles;
        break;
    case GLFW_KEY_W:
        views_.voxels = !views_.voxels;
        break;
    case GLFW_KEY_E:
        // As in the seed: one more level of subdivision. With an octree that is twice the voxels per
        // wind cell per axis (up to gust's 8).
        if (domain_.voxels_per_cell < 8) {
            options_.voxels_per_cell = domain_.voxels_per_cell * 2;
            rebuild_wind_ = true;
        }
        break;
    case GLFW_KEY_R:
        views_.nodes = !views_.nodes;
        break;
    case GLFW_KEY_T:
        views_.slice = !views_.slice;
        break;
    case GLFW_KEY_Y:
        views_.arrows = !views_.arrows;
        break;
    case GLFW_KEY_F:
        camera_.follow = !camera_.follow;
        break;
    case GLFW_KEY_H:
        show_hud_ = !show_hud_;
        break;
    case GLFW_KEY_SPACE:
        paused_ = !paused_;
        break;
    case GLFW_KEY_ESCAPE:
        glfwSetWindowShouldClose(window_, GLFW_TRUE);
        break;
    default:
        break;
    }
}

void Game::make_wind() {
    wind_.reset();
    gust::HostDevice host = vk_->gust_host();
    gust::SystemDesc desc;
    desc.host = &host;
    desc.domain.cells[0] = options_.wind_cells[0];
    desc.domain.cells[1] = options_.wind_cells[1];
    desc.domain.cells[2] = options_.wind_cells[2];
    desc.domain.cell_size = options_.cell_size;
    desc.domain.voxels_per_cell = options_.voxels_per_cell;
    // An octree, as in the seed, so that E (one more level) doubles the resolution.
    desc.domain.branching = 2;
    // The domain's floor sits just under the ground so the grass roots are inside it.
    desc.domain.focus = domain_centre(glm::vec3(0.0f), options_.cell_size, options_.wind_cells[1]);
    desc.wind.max_cycles = options_.max_cycles;
    desc.wind.tolerance = 1e-3f;
    if (gust::Outcome made = gust::System::create(desc, wind_); !made)
        throw std::runtime_error("gust::System::create: " + made.message());
    domain_ = desc.domain;
    world_->attach(*wind_);
    renderer_->set_wind(wind_->wind_texture(), domain_);
    last_nodes_.clear();
}

void Game::refresh_debug_views() {
    if (views_.voxels) {
        // Sized from the stats, so the tree is downloaded once.
        gust::VoxelGridInfo grid;
        std::vector<gust::VoxelCoord> voxels(wind_->stats().voxels);
        std::size_t count = 0;
        if (wind_->debug_voxel_grid(grid) && wind_->debug_voxels(voxels, count)) {
            voxels.resize(std::min(count, voxels.size()));
            renderer_->set_voxels(grid, voxels);
        }
    }
    if (views_.nodes) {
        std::vector<gust::TreeNode> nodes(wind_->stats().nodes);
        std::size_t count = 0;
        if (!wind_->debug_tree_nodes(nodes, count)) return;
        nodes.resize(std::min(count, nodes.size()));
        // Colour by what changed since the last frame: new nodes (refined) green, nodes gone (coarsened)
        // red, the rest grey, darker the deeper.
        std::vector<LineVertex> lines;
        std::set<NodeKey> now;
        nodes_per_level_.clear();
        const auto root =
            std::find_if(nodes.begin(), nodes.end(), [](const gust::TreeNode& n) { return n.level == 0; });
        if (root == nodes.end()) return;
        const glm::vec3 root_min(root->min.x, root->min.y, root->min.z);
        const float root_size = root->size;
        // A node's key is its level and its corner in units of its own size, counted from the root's corner.
        auto size_at = [&](std::uint32_t level) {
            return root_size / std::pow(2.0f, static_cast<float>(level));
        };
        for (const gust::TreeNode& n : nodes) {
            const glm::vec3 corner = (glm::vec3(n.min.x, n.min.y, n.min.z) - root_min) / size_at(n.level);
            const NodeKey key{n.level, std::llround(corner.x), std::llround(corner.y),
                              std::llround(corner.z)};
            now.insert(key);
            ++nodes_per_level_[n.level];
            const bool refined = !last_nodes_.empty() && !last_nodes_.count(key);
            const float shade = 0.9f - 0.1f * static_cast<float>(n.level);
            add_box(lines, {n.min.x, n.min.y, n.min.z}, n.size,
                    refined ? glm::vec4(0.1f, 0.95f, 0.2f, 1.0f) : glm::vec4(shade, shade, shade, 1.0f));
        }
        for (const NodeKey& gone : last_nodes_)
            if (!now.count(gone)) {
                const float size = size_at(std::get<0>(gone));
                const glm::vec3 corner(static_cast<float>(std::get<1>(gone)),
                                       static_cast<float>(std::get<2>(gone)),
                                       static_cast<float>(std::get<3>(gone)));
                add_box(lines, root_min + corner * size, size, glm::vec4(0.95f, 0.15f, 0.1f, 1.0f));
            }
        last_nodes_ = std::move(now);
        renderer_->set_lines(lines);
    }
}

void Game::build_hud(double frame_ms) {
    if (!show_hud_) return;
    const gust::FrameStats& s = wind_->stats();
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.75f);
    ImGui::Begin("gust", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::Text("%.1f fps (%.1f ms a frame)", fps_, frame_ms);
    double gpu_total = 0.0;
    for (const auto& pass : s.ms)
        gpu_total += pass.second;
    ImGui::Text("gust: %.1f ms GPU, %u pressure iterations", gpu_total, s.cycles);
    ImGui::Text("wind %ux%ux%u cells of %.2f m, %u voxels per cell", domain_.cells[0], domain_.cells[1],
                domain_.cells[2], domain_.cell_size, domain_.voxels_per_cell);
    ImGui::TextDisabled("Q tris  W voxels  E subdivide  R nodes  T slice  Y arrows  F follow");
    if (ImGui::CollapsingHeader("GPU ms per pass")) {
        for (const auto& [name, ms] : s.ms)
            ImGui::Text("%-18s %7.2f", name.c_str(), ms);
    }
    if (ImGui::CollapsingHeader("tree and memory", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Text("nodes %llu (+%llu refined, -%llu coarsened blocks)",
                    static_cast<unsigned long long>(s.nodes), static_cast<unsigned long long>(s.refined),
                    static_cast<unsigned long long>(s.coarsened));
        if (!nodes_per_level_.empty()) {
            std::string levels;
            for (const auto& [level, n] : nodes_per_level_)
                levels += std::to_string(n) + " ";
            ImGui::Text("per level: %s", levels.c_str());
        }
        ImGui::Text("voxels %llu, fragments %llu", static_cast<unsigned long long>(s.voxels),
                    static_cast<unsigned long long>(s.fragments));
        ImGui::Text("tree %.1f KiB, fragments %.1f KiB, dense grid %.1f KiB",
                    static_cast<double>(s.pool_bytes) / 1024.0,
                    static_cast<double>(s.fragment_bytes) / 1024.0,
                    static_cast<double>(s.dense_bytes) / 1024.0);
        ImGui::Text("pressure: %u iterations, residual %.2e%s", s.cycles, s.residual,
                    s.converged ? "" : " (capped)");
    }
    if (ImGui::CollapsingHeader("wind controls")) {
        WorldSettings& w = world_->settings();
        ImGui::SliderFloat("ambient m/s", &w.wind_speed, 0.0f, 12.0f);
        ImGui::SliderFloat("heading", &w.wind_heading_deg, -180.0f, 180.0f);
        ImGui::SliderFloat("gustiness", &w.gustiness, 0.0f, 1.0f);
        ImGui::Checkbox("fan", &w.fan_on);
        ImGui::SameLine();
        ImGui::SliderFloat("fan m/s", &w.fan_strength, 0.0f, 15.0f);
        ImGui::Checkbox("flyer's motor", &w.flyer_motor_on);
        ImGui::SliderFloat("walk speed", &w.walk_speed, 0.0f, 2.0f);
        int cells[3] = {static_cast<int>(options_.wind_cells[0]), static_cast<int>(options_.wind_cells[1]),
                        static_cast<int>(options_.wind_cells[2])};
        if (ImGui::SliderInt3("cells", cells, 8, 64)) {
            for (int i = 0; i < 3; ++i)
                options_.wind_cells[i] = static_cast<std::uint32_t>(cells[i]);
        }
        if (ImGui::Button("apply resolution")) rebuild_wind_ = true;
    }
    if (ImGui::CollapsingHeader("views")) {
        ImGui::Checkbox("Q triangles", &views_.triangles);
        ImGui::Checkbox("W voxels", &views_.voxels);
        ImGui::Checkbox("R tree nodes (green refined, red coarsened)", &views_.nodes);
        ImGui::Checkbox("T wind slice", &views_.slice);
        ImGui::SameLine();
        ImGui::Checkbox("Y arrows", &views_.arrows);
        ImGui::SliderFloat("slice height", &views_.slice_height, 0.1f, 8.0f);
        ImGui::Checkbox("F follow the fox", &camera_.follow);
        ImGui::Text("E: one more tree level; drag: orbit; wheel: zoom; space: pause; H: hide");
    }
    ImGui::End();
}

void Game::write_stats(std::ofstream& stats, std::uint64_t frame, double t, double frame_ms, double wind_ms) {
    const gust::FrameStats& s = wind_->stats();
    nlohmann::json line;
    line["frame"] = frame;
    line["time"] = t;
    line["frame_ms"] = frame_ms;
    line["wind_cpu_ms"] = wind_ms;
    line["fragments"] = s.fragments;
    line["voxels"] = s.voxels;
    line["nodes"] = s.nodes;
    line["refined"] = s.refined;
    line["coarsened"] = s.coarsened;
    line["cycles"] = s.cycles;
    line["residual"] = s.residual;
    line["converged"] = s.converged;
    nlohmann::json ms = nlohmann::json::object();
    for (const auto& [name, value] : s.ms)
        ms[std::string(name)] = value;
    line["gpu_ms"] = ms;
    const glm::vec3 ambient = world_->ambient(t);
    line["ambient"] = {ambient.x, ambient.y, ambient.z};
    const auto [mean, largest] = renderer_->grass_bend();
    line["grass_bend_mean"] = mean;
    line["grass_bend_max"] = largest;
    stats << line.dump() << "\n";
}

int Game::run() {
    const bool windowed = open_window();
    if (!windowed) {
        if (options_.frames == 0) options_.frames = 300;
        if (options_.out.empty()) options_.out = "out/sample";
    }
    std::vector<const char*> extensions;
    if (windowed) {
        std::uint32_t count = 0;
        const char** names = glfwGetRequiredInstanceExtensions(&count);
        extensions.assign(names, names + count);
    }
    vk_ = std::make_unique<VulkanHost>(extensions, options_.validation, windowed);
    std::fprintf(stderr, "gust_sample: %s on %s, %u grass blades\n", windowed ? "windowed" : "headless",
                 vk_->properties().deviceName, options_.world.grass_blades);
    world_ = std::make_unique<World>(options_.assets, options_.world);
    if (windowed)
        swapchain_ = std::make_unique<Swapchain>(*vk_, window_);
    else
        offscreen_ = std::make_unique<Offscreen>(*vk_, VkExtent2D{options_.width, options_.height});
    renderer_ = std::make_unique<Renderer>(
        *vk_, *world_, windowed ? swapchain_->format() : Offscreen::kFormat,
        windowed ? VK_IMAGE_LAYOUT_PRESENT_SRC_KHR : VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    hud_ = std::make_unique<Hud>(*vk_, renderer_->render_pass(), windowed ? swapchain_->image_count() : 2,
                                 window_, VkExtent2D{options_.width, options_.height});
    make_wind();
    views_ = options_.views;
    camera_.follow = options_.follow;
    show_hud_ = options_.hud;

    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = vk_->command_pool();
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    check(vkAllocateCommandBuffers(vk_->device(), &alloc, &cmd_), "vkAllocateCommandBuffers");
    VkFenceCreateInfo fence{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    check(vkCreateFence(vk_->device(), &fence, nullptr, &fence_), "vkCreateFence");

    std::ofstream stats;
    if (!options_.out.empty()) {
        std::filesystem::create_directories(options_.out);
        stats.open(options_.out / "stats.jsonl");
        if (!stats) throw std::runtime_error("cannot write " + (options_.out / "stats.jsonl").string());
    }

    double t = 0.0;
    std::uint64_t frame = 0;
    double loop_ms = 0.0, steady_ms = 0.0;
    Clock::time_point last = Clock::now();
    while (options_.frames == 0 || frame < options_.frames) {
        if (windowed) {
            glfwPollEvents();
            if (glfwWindowShouldClose(window_)) break;
        }
        const Clock::time_point start = Clock::now();
        const float wall_dt = std::min(0.1f, static_cast<float>(ms_since(last) / 1000.0));
        last = start;
        // Headless runs step a fixed dt so their frames do not depend on the machine's speed.
        const float dt = paused_ ? 0.0f : (windowed ? std::max(wall_dt, 1e-3f) : options_.dt);
        if (rebuild_wind_) {
            rebuild_wind_ = false;
            vkDeviceWaitIdle(vk_->device());
            make_wind();
        }
        t += dt;
        world_->update(t);
        const glm::vec3 fox = world_->follow_target();
        camera_.target = camera_.follow ? fox : glm::vec3(0.0f, 1.0f, 0.0f);
        if (!windowed) camera_.yaw = 2.4f + 0.02f * static_cast<float>(t);
        const Clock::time_point wind_start = Clock::now();
        if (dt > 0.0f) {
            const glm::vec3 focus = camera_.follow ? fox : glm::vec3(0.0f);
            wind_->set_focus(domain_centre(focus, domain_.cell_size, domain_.cells[1]));
            if (gust::Outcome stepped = world_->step_wind(*wind_, dt, t); !stepped)
                throw std::runtime_error("gust step: " + stepped.message());
        }
        const double wind_ms = ms_since(wind_start);
        refresh_debug_views();
        renderer_->update_world(*world_);

        Target target;
        bool recreated = false;
        if (windowed) {
            if (!swapchain_->acquire(target, recreated)) {
                if (recreated) renderer_->forget_targets();
                continue;
            }
        } else {
            target = offscreen_->target();
        }
        hud_->begin_frame(dt);
        build_hud(loop_ms);
        vkResetCommandBuffer(cmd_, 0);
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        vkBeginCommandBuffer(cmd_, &begin);
        FrameView view;
        view.view_proj = camera_.view_proj(static_cast<float>(target.extent.width) /
                                           static_cast<float>(std::max(target.extent.height, 1u)));
        view.eye = camera_.eye();
        view.time = static_cast<float>(t);
        view.dt = dt;
        const gust::Vec3 origin = wind_->domain_origin();
        view.wind_origin = {origin.x, origin.y, origin.z};
        renderer_->record(cmd_, target.view, target.extent, view, views_,
                          [&](VkCommandBuffer c) { hud_->draw(c); });
        if (!windowed) offscreen_->record_readback(cmd_);
        vkEndCommandBuffer(cmd_);
        if (windowed) {
            swapchain_->submit_and_present(cmd_, fence_, recreated);
        } else {
            offscreen_->submit(cmd_, fence_);
        }
        check(vkWaitForFences(vk_->device(), 1, &fence_, VK_TRUE, UINT64_MAX), "vkWaitForFences");
        check(vkResetFences(vk_->device(), 1, &fence_), "vkResetFences");
        if (recreated) renderer_->forget_targets();
        loop_ms = ms_since(start);
        // The first frame voxelizes the static scene and builds pipelines: leave it out of the rate.
        if (frame > 0) steady_ms += loop_ms;
        fps_ = frame > 0 ? 1000.0 * static_cast<double>(frame) / steady_ms : 0.0;
        if (stats.is_open()) write_stats(stats, frame, t, loop_ms, wind_ms);
        if (!windowed && !options_.out.empty() && frame % options_.png_every == 0) {
            char name[32];
            std::snprintf(name, sizeof(name), "frame_%04llu.png", static_cast<unsigned long long>(frame));
            offscreen_->write_png(options_.out / name);
        }
        if (!windowed && frame % 30 == 0)
            std::fprintf(stderr, "gust_sample: frame %llu, %.1f fps\n",
                         static_cast<unsigned long long>(frame), fps_);
        ++frame;
    }
    vkDeviceWaitIdle(vk_->device());
    std::printf(
        "gust_sample: %llu frames, %.1f fps (mean frame %.1f ms after the first; PNG writing excluded)\n",
        static_cast<unsigned long long>(frame), fps_,
        frame > 1 ? steady_ms / static_cast<double>(frame - 1) : 0.0);
    if (vk_->validation_messages() > 0) {
        std::fprintf(stderr, "gust_sample: %u validation messages\n", vk_->validation_messages());
        return 1;
    }
    return 0;
}

} // namespace

int run_game(const GameOptions& options) {
    try {
        Game game(options);
        return game.run();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gust_sample: error: %s\n", e.what());
        return 1;
    }
}

} // namespace sample
