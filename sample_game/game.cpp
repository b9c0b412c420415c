#include "game.hpp"

#include "camera.hpp"
#include "display.hpp"
#include "hud.hpp"
#include "overlay.hpp"
#include "renderer.hpp"
#include "tour.hpp"
#include "video.hpp"

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <set>
#include <span>
#include <tuple>
#include <vector>

namespace sample {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

/// The headless time step when --dt does not set one, s.
constexpr float kHeadlessDt = 1.0f / 30.0f;
/// Frames of a headless run without the tour and without --frames.
constexpr std::uint32_t kFreeRunFrames = 300;
/// Where the camera looks when it follows nothing: the middle of the field.
constexpr glm::vec3 kFieldCentre{0.0f, 1.0f, 0.0f};

/// Where gust's domain is centred for a focus on the ground at `focus`: the domain's floor sits 1 m under
/// the ground so that the ground is a solid inside it.
gust::Vec3 domain_centre(glm::vec3 focus, float cell_size, std::uint32_t cells_y) {
    return {focus.x, focus.y + 0.5f * cell_size * static_cast<float>(cells_y) - 1.0f, focus.z};
}

/// Key of a tree node for telling this frame's nodes from last frame's.
using NodeKey = std::tuple<std::uint32_t, std::int64_t, std::int64_t, std::int64_t>;

/// Frames a tree node stays green after it is made, or red after it is freed (a second at the headless
/// 30 frames a second): a walker's nodes change in one frame of many, too briefly to see otherwise.
constexpr std::uint32_t kNodeChangeFrames = 30;

/// Twelve edges of the box [lo, hi] as line vertices.
void add_box(std::vector<LineVertex>& out, glm::vec3 lo, glm::vec3 hi, glm::vec4 colour) {
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
    /// A person moved the camera or changed a view: the tour gives them the camera.
    void take_over() { touring_ = false; }
    /// Points the camera (and, touring, sets the views) for the frame that starts at world time `start`.
    void direct_camera(bool windowed, double start);
    void build_overlay(bool windowed);
    void refresh_debug_views();
    void write_stats(std::ofstream& stats, std::uint64_t frame, double frame_ms, double wind_ms);
    void write_video(const std::vector<std::filesystem::path>& frames, float dt) const;

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
    Quality quality_ = Quality::Low; ///< resolved preset
    Detail detail_; ///< the preset with the command line's overrides; E and the panels change it
    OrbitCamera camera_;
    Views views_;
    bool follow_ = false;
    bool fly_ = false; ///< GameOptions::fly
    bool touring_ = false;
    double tour_start_ = 0.0; ///< world time at which the tour (re)started, s
    TourFrame tour_frame_;    ///< this frame's shot while touring
    double t_ = 0.0;          ///< world time, s
    bool paused_ = false, show_hud_ = true, panels_ = false, rebuild_wind_ = false;
    double fps_ = 0.0, loop_ms_ = 0.0;
    std::set<NodeKey> last_nodes_;
    std::map<NodeKey, std::uint32_t> made_; ///< nodes made in the last kNodeChangeFrames frames: frames since
    std::map<NodeKey, std::uint32_t> freed_; ///< nodes freed in the last kNodeChangeFrames frames: the same
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
        game->take_over();
        game->camera_.yaw += 0.008f * static_cast<float>(x - game->drag_x_);
        game->camera_.pitch =
            std::clamp(game->camera_.pitch + 0.008f * static_cast<float>(y - game->drag_y_), 0.05f, 1.5f);
        game->drag_x_ = x;
        game->drag_y_ = y;
    });
    glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double dy) {
        auto* game = static_cast<Game*>(glfwGetWindowUserPointer(w));
        if (game->hud_ && game->hud_->wants_mouse()) return;
        game->take_over();
        game->camera_.distance =
            std::clamp(game->camera_.distance * std::pow(0.9f, static_cast<float>(dy)), 2.0f, 120.0f);
    });
    return true;
}

void Game::on_key(int key) {
    // The camera and view keys hand the camera to the person; the tour would undo them on the next frame.
    switch (key) {
    case GLFW_KEY_Q:
        take_over();
        views_.triangles = !views_.triangles;
        break;
    case GLFW_KEY_G:
        take_over();
        views_.grass = !views_.grass;
        break;
    case GLFW_KEY_W:
        take_over();
        views_.voxels = !views_.voxels;
        break;
    case GLFW_KEY_E:
        // As in the seed: one more level of subdivision. With an octree that is twice the voxels per
        // wind cell per axis (up to gust's 8).
        if (domain_.voxels_per_cell < 8) {
            detail_.voxels_per_cell = domain_.voxels_per_cell * 2;
            rebuild_wind_ = true;
        }
        break;
    case GLFW_KEY_R:
        take_over();
        views_.nodes = !views_.nodes;
        break;
    case GLFW_KEY_T:
        take_over();
        views_.slice = !views_.slice;
        break;
    case GLFW_KEY_Y:
        take_over();
        views_.arrows = !views_.arrows;
        break;
    case GLFW_KEY_F:
        take_over();
        follow_ = !follow_;
        if (!follow_) camera_.target = kFieldCentre;
        break;
    case GLFW_KEY_C:
        // The tour starts from its first shot and films the field, so the domain stops following the fox.
        touring_ = !touring_;
        tour_start_ = t_;
        if (touring_) follow_ = false;
        break;
    case GLFW_KEY_H:
        show_hud_ = !show_hud_;
        break;
    case GLFW_KEY_TAB:
        panels_ = !panels_;
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
    desc.domain.cells[0] = detail_.cells[0];
    desc.domain.cells[1] = detail_.cells[1];
    desc.domain.cells[2] = detail_.cells[2];
    desc.domain.cell_size = detail_.cell_size;
    desc.domain.voxels_per_cell = detail_.voxels_per_cell;
    // An octree, as in the seed, so that E (one more level) doubles the resolution.
    desc.domain.branching = 2;
    // Nested cascades around the village reach over the valley (docs/sample.md, "Cascades").
    desc.domain.cascades = detail_.cascades;
    desc.domain.ratio = detail_.ratio;
    // The domain's floor sits just under the ground so the grass roots are inside it.
    desc.domain.focus = domain_centre(glm::vec3(0.0f), detail_.cell_size, detail_.cells[1]);
    // A game's fixed budget (the preset's V-cycles a frame), stopping early once the divergence left is
    // 1 % of what the frame brought: grass cannot see less (docs/sample.md, "Quality presets").
    desc.wind.max_cycles = detail_.max_cycles;
    desc.wind.cycles_per_step = detail_.max_cycles;
    desc.wind.tolerance = 1e-2f;
    if (gust::Outcome made = gust::System::create(desc, wind_); !made)
        throw std::runtime_error("gust::System::create: " + made.message());
    domain_ = desc.domain;
    world_->attach(*wind_);
    renderer_->set_wind(wind_->wind_textures(), domain_);
    last_nodes_.clear();
    made_.clear();
    freed_.clear();
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
    std::vector<LineVertex> lines;
    if (views_.cascades) {
        // Each cascade's extent, finest first, from yellow to purple.
        const std::span<const gust::WindTexture> textures = wind_->wind_textures();
        for (std::size_t k = 0; k < textures.size(); ++k) {
            glm::mat4 to_texture;
            std::copy_n(textures[k].world_to_texture.m, 16, &to_texture[0][0]);
            const glm::mat4 to_world = glm::inverse(to_texture);
            const float f =
                static_cast<float>(k) / static_cast<float>(std::max<std::size_t>(textures.size() - 1, 1));
            add_box(lines, glm::vec3(to_world * glm::vec4(0.0f, 0.0f, 0.0f, 1.0f)),
                    glm::vec3(to_world * glm::vec4(1.0f, 1.0f, 1.0f, 1.0f)),
                    glm::vec4(glm::mix(glm::vec3(1.0f, 0.9f, 0.1f), glm::vec3(0.7f, 0.2f, 0.9f), f), 1.0f));
        }
    }
    if (!views_.nodes) {
        // Nothing to compare the next frame's nodes with: when R comes on again, its first frame is all kept.
        last_nodes_.clear();
        made_.clear();
        freed_.clear();
        nodes_per_level_.clear();
    } else {
        std::vector<gust::TreeNode> nodes(wind_->stats().nodes);
        std::size_t count = 0;
        if (!wind_->debug_tree_nodes(nodes, count)) return;
        nodes.resize(std::min(count, nodes.size()));
        // Colour by what changed lately: nodes made in the last kNodeChangeFrames frames (refined) green,
        // nodes freed in them (coarsened) red, the rest grey, darker the deeper.
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
        auto age = [](std::map<NodeKey, std::uint32_t>& ages) {
            for (auto it = ages.begin(); it != ages.end();)
                it = ++it->second >= kNodeChangeFrames ? ages.erase(it) : std::next(it);
        };
        age(made_);
        age(freed_);
        for (const gust::TreeNode& n : nodes) {
            const glm::vec3 corner = (glm::vec3(n.min.x, n.min.y, n.min.z) - root_min) / size_at(n.level);
            now.insert({n.level, std::llround(corner.x), std::llround(corner.y), std::llround(corner.z)});
        }
        if (!last_nodes_.empty()) {
            for (const NodeKey& key : now)
                if (!last_nodes_.count(key)) {
                    made_[key] = 0;
                    freed_.erase(key);
                }
            for (const NodeKey& gone : last_nodes_)
                if (!now.count(gone)) {
                    freed_[gone] = 0;
                    made_.erase(gone);
                }
        }
        for (const gust::TreeNode& n : nodes) {
            const glm::vec3 corner = (glm::vec3(n.min.x, n.min.y, n.min.z) - root_min) / size_at(n.level);
            const NodeKey key{n.level, std::llround(corner.x), std::llround(corner.y),
                              std::llround(corner.z)};
            ++nodes_per_level_[n.level];
            const bool refined = made_.count(key) > 0;
            if (!views_.every_node && !refined && n.state != gust::TreeNodeState::Reached) continue;
            const float shade = 0.9f - 0.1f * static_cast<float>(n.level);
            const glm::vec3 lo(n.min.x, n.min.y, n.min.z);
            add_box(lines, lo, lo + n.size,
                    refined ? glm::vec4(0.1f, 0.95f, 0.2f, 1.0f) : glm::vec4(shade, shade, shade, 1.0f));
        }
        for (const auto& [gone, frames] : freed_) {
            const float size = size_at(std::get<0>(gone));
            const glm::vec3 corner(static_cast<float>(std::get<1>(gone)),
                                   static_cast<float>(std::get<2>(gone)),
                                   static_cast<float>(std::get<3>(gone)));
            const glm::vec3 lo = root_min + corner * size;
            add_box(lines, lo, lo + size, glm::vec4(0.95f, 0.15f, 0.1f, 1.0f));
        }
        last_nodes_ = std::move(now);
    }
    if (views_.nodes || views_.cascades) renderer_->set_lines(lines);
}

void Game::direct_camera(bool windowed, double start) {
    if (touring_) {
        // The tour's clock reads 0 on its first frame, so N frames of dt show [0, N dt) of it.
        tour_frame_ = tour_at(start - tour_start_, world_->stage());
        camera_ = tour_frame_.camera;
        views_ = tour_frame_.views;
    } else if (fly_) {
        // From above and behind the flight's heading (it circles anticlockwise seen from above), far enough
        // to see the cascades' ground go by.
        camera_.target = world_->flight_at(t_);
        const glm::vec3 ahead = world_->flight_at(t_ + 1.0) - camera_.target;
        camera_.yaw = std::atan2(-ahead.z, -ahead.x);
        camera_.pitch = 0.6f;
        camera_.distance = 60.0f;
    } else if (follow_) {
        camera_.target = world_->follow_target();
    } else if (!windowed) {
        // Without the tour a headless run circles the field slowly, as it always has.
        camera_.yaw = 2.4f + 0.02f * static_cast<float>(t_);
    }
}

void Game::build_overlay(bool windowed) {
    if (!show_hud_) return;
    OverlayReport report;
    report.fps = fps_;
    report.frame_ms = loop_ms_;
    report.stats = &wind_->stats();
    report.domain = domain_;
    report.quality = quality_;
    report.windowed = windowed;
    report.touring = touring_;
    draw_stats_bar(report);
    if (touring_) draw_caption(tour_frame_);
    if (!panels_) return;
    const PanelActions actions =
        draw_panels(report, {world_->settings(), views_, follow_, detail_.cells, nodes_per_level_});
    if (actions.camera_or_views_changed) take_over();
    if (actions.apply_resolution) rebuild_wind_ = true;
}

void Game::write_stats(std::ofstream& stats, std::uint64_t frame, double frame_ms, double wind_ms) {
    const gust::FrameStats& s = wind_->stats();
    nlohmann::json line;
    line["frame"] = frame;
    line["time"] = t_;
    if (touring_) line["shot"] = tour_frame_.shot->key;
    line["views"] = view_letters(views_);
    line["follow"] = follow_;
    const gust::Vec3 origin = wind_->domain_origin();
    line["domain_origin"] = {origin.x, origin.y, origin.z};
    const glm::vec3 eye = camera_.eye();
    line["eye"] = {eye.x, eye.y, eye.z};
    line["quality"] = quality_name(quality_);
    line["cells"] = {domain_.cells[0], domain_.cells[1], domain_.cells[2]};
    line["cell_size"] = domain_.cell_size;
    line["voxels_per_cell"] = domain_.voxels_per_cell;
    line["grass"] = world_->grass_count();
    line["max_iterations"] = detail_.max_cycles;
    line["cascades"] = domain_.cascades;
    line["ratio"] = domain_.ratio;
    line["frame_ms"] = frame_ms;
    line["wind_cpu_ms"] = wind_ms;
    line["fragments"] = s.fragments;
    line["voxels"] = s.voxels;
    line["nodes"] = s.nodes;
    line["refined"] = s.refined;
    line["coarsened"] = s.coarsened;
    line["cycles"] = s.cycles;
    line["residual"] = s.residual;
    line["divergence_before"] = s.divergence_before;
    line["converged"] = s.converged;
    line["diverged"] = s.diverged;
    line["dispatches"] = s.dispatches;
    line["stages"] = s.stages;
    line["submissions"] = s.submissions;
    line["waits"] = s.waits;
    nlohmann::json ms = nlohmann::json::object();
    for (const auto& [name, value] : s.ms)
        ms[std::string(name)] = value;
    line["gpu_ms"] = ms;
    const glm::vec3 ambient = world_->ambient(t_);
    line["ambient"] = {ambient.x, ambient.y, ambient.z};
    const auto [mean, largest] = renderer_->grass_bend();
    line["grass_bend_mean"] = mean;
    line["grass_bend_max"] = largest;
    // The groves on the ridge's crest and in its lee: the lee's crowns bend less (docs/sample.md).
    for (const char* grove : {"crest", "lee"}) {
        std::vector<std::uint32_t> slots;
        for (const WorldObject& o : world_->objects())
            if (o.name == std::string(grove) + " tree") slots.push_back(o.foliage_slot);
        line[std::string(grove) + "_bend"] = renderer_->crown_bend(slots);
    }
    // Flushed each frame: a run stopped from outside (or watched while it runs) keeps every frame's line.
    stats << line.dump() << "\n" << std::flush;
}

void Game::write_video(const std::vector<std::filesystem::path>& frames, float dt) const {
    const double frame_s = double(dt) * options_.png_every;
    const int frame_ms = static_cast<int>(std::lround(1000.0 * frame_s));
    // One pass of the tour at the most: a long run's every frame would make a video of hundreds of MB.
    const std::size_t most = std::max<std::size_t>(2, std::size_t(std::ceil(tour_seconds() / frame_s)));
    const std::span<const std::filesystem::path> shown(frames.data(), std::min(frames.size(), most));
    const VideoOutcome video =
        write_animated_webp(shown, frame_ms, options_.out / (options_.tour ? "tour.webp" : "frames.webp"));
    std::fprintf(stderr, "gust_sample: %s\n", video.message.c_str());
}

int Game::run() {
    const bool windowed = open_window();
    // Headless runs step a fixed dt so their frames do not depend on the machine's speed; windowed runs
    // follow the clock unless --dt fixes the step (a test's windowed tour).
    const float fixed_dt = options_.dt.value_or(kHeadlessDt);
    const bool fixed_step = !windowed || options_.dt.has_value();
    if (!windowed) {
        if (options_.frames == 0)
            options_.frames = options_.tour
                                  ? static_cast<std::uint32_t>(std::ceil(tour_seconds() / fixed_dt - 1e-6))
                                  : kFreeRunFrames;
        if (options_.out.empty()) options_.out = "out/sample";
    }
    std::vector<const char*> extensions;
    if (windowed) {
        std::uint32_t count = 0;
        const char** names = glfwGetRequiredInstanceExtensions(&count);
        extensions.assign(names, names + count);
    }
    vk_ = std::make_unique<VulkanHost>(extensions, options_.validation, windowed);
    const VkPhysicalDeviceType device_type = vk_->properties().deviceType;
    quality_ = resolve(options_.quality, device_type);
    detail_ = apply(preset(quality_), options_.detail);
    options_.world.grass_blades = detail_.grass_blades;
    std::fprintf(stderr,
                 "gust_sample: %s on %s, %s; quality %s%s: %ux%ux%u cells of %.2f m, %u voxels per cell, %u "
                 "grass blades, %u pressure iterations a frame, %u cascades of ratio %u\n",
                 windowed ? "windowed" : "headless", vk_->properties().deviceName,
                 device_type_words(device_type), quality_name(quality_),
                 options_.quality == Quality::Auto ? " (auto)" : "", detail_.cells[0], detail_.cells[1],
                 detail_.cells[2], detail_.cell_size, detail_.voxels_per_cell, detail_.grass_blades,
                 detail_.max_cycles, detail_.cascades, detail_.ratio);
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
    follow_ = options_.follow;
    fly_ = options_.fly;
    // The flight shows what it is for: the cascades' extents moving over the ground, and the wind.
    if (fly_) views_.cascades = views_.slice = true;
    touring_ = options_.tour;
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

    std::uint64_t frame = 0;
    double steady_ms = 0.0;
    std::vector<std::filesystem::path> pngs;
    Clock::time_point last = Clock::now();
    while (options_.frames == 0 || frame < options_.frames) {
        if (windowed) {
            glfwPollEvents();
            if (glfwWindowShouldClose(window_)) break;
        }
        const Clock::time_point start = Clock::now();
        const float wall_dt = std::min(0.1f, static_cast<float>(ms_since(last) / 1000.0));
        last = start;
        const float dt = paused_ ? 0.0f : (fixed_step ? fixed_dt : std::max(wall_dt, 1e-3f));
        if (rebuild_wind_) {
            rebuild_wind_ = false;
            vkDeviceWaitIdle(vk_->device());
            make_wind();
        }
        const double start_t = t_;
        t_ += dt;
        world_->update(t_);
        direct_camera(windowed, start_t);
        const Clock::time_point wind_start = Clock::now();
        if (dt > 0.0f) {
            const glm::vec3 focus = fly_      ? world_->flight_at(t_)
                                    : follow_ ? world_->follow_target()
                                              : glm::vec3(0.0f);
            wind_->set_focus(domain_centre(focus, domain_.cell_size, domain_.cells[1]));
            if (gust::Outcome stepped = world_->step_wind(*wind_, dt, t_); !stepped)
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
        build_overlay(windowed);
        vkResetCommandBuffer(cmd_, 0);
        VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        vkBeginCommandBuffer(cmd_, &begin);
        FrameView view;
        view.view_proj = camera_.view_proj(static_cast<float>(target.extent.width) /
                                           static_cast<float>(std::max(target.extent.height, 1u)));
        view.eye = camera_.eye();
        view.time = static_cast<float>(t_);
        view.dt = dt;
        const gust::Vec3 origin = wind_->domain_origin();
        view.wind_origin = {origin.x, origin.y, origin.z};
        view.ambient = world_->ambient(t_);
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
        loop_ms_ = ms_since(start);
        // The first frame voxelizes the static scene and builds pipelines: leave it out of the rate.
        if (frame > 0) steady_ms += loop_ms_;
        fps_ = frame > 0 ? 1000.0 * static_cast<double>(frame) / steady_ms : 0.0;
        if (stats.is_open()) write_stats(stats, frame, loop_ms_, wind_ms);
        if (!windowed && !options_.out.empty() && frame % options_.png_every == 0) {
            char name[32];
            std::snprintf(name, sizeof(name), "frame_%04llu.png", static_cast<unsigned long long>(frame));
            pngs.push_back(options_.out / name);
            offscreen_->write_png(pngs.back());
        }
        if (!windowed && frame % 30 == 0)
            std::fprintf(stderr, "gust_sample: frame %llu, %.1f fps%s%s\n",
                         static_cast<unsigned long long>(frame), fps_, touring_ ? ", shot " : "",
                         touring_ ? tour_frame_.shot->key : "");
        ++frame;
    }
    vkDeviceWaitIdle(vk_->device());
    std::printf(
        "gust_sample: %llu frames, %.1f fps (mean frame %.1f ms after the first; PNG writing excluded)\n",
        static_cast<unsigned long long>(frame), fps_,
        frame > 1 ? steady_ms / static_cast<double>(frame - 1) : 0.0);
    std::fflush(stdout);
    if (options_.video && pngs.size() >= 2) write_video(pngs, fixed_dt);
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
