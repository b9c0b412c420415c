#include "overlay.hpp"

#include <algorithm>
#include <cstdio>
#include <imgui.h>
#include <initializer_list>
#include <string>

namespace sample {

namespace {

// Labels size themselves here rather than with AlwaysAutoResize, which hides a window on its first frame
// while it measures itself: the first frame of a headless run would have no overlay.
constexpr ImGuiWindowFlags kLabel = ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_NoInputs |
                                    ImGuiWindowFlags_NoNav | ImGuiWindowFlags_NoFocusOnAppearing |
                                    ImGuiWindowFlags_NoSavedSettings;

double gpu_ms(const gust::FrameStats& stats) {
    double total = 0.0;
    for (const auto& pass : stats.ms)
        total += pass.second;
    return total;
}

/// Lines of text as a label shows them: each wrapped at `wrap` pixels, one item spacing apart.
ImVec2 text_block(std::initializer_list<const char*> lines, float wrap) {
    ImVec2 size(0.0f, 0.0f);
    for (const char* line : lines) {
        const ImVec2 s = ImGui::CalcTextSize(line, nullptr, false, wrap);
        size.x = std::max(size.x, s.x);
        size.y += s.y + (size.y > 0.0f ? ImGui::GetStyle().ItemSpacing.y : 0.0f);
    }
    return size;
}

} // namespace

void draw_stats_bar(const OverlayReport& report) {
    const gust::FrameStats& s = *report.stats;
    const gust::WindDomain& d = report.domain;
    char stats[256];
    std::snprintf(
        stats, sizeof(stats),
        "%.1f fps | gust %.1f ms GPU | %ux%ux%u cells of %.2f m, %u vox | tree +%llu -%llu blocks | "
        "residual %.1e | %s",
        report.fps, gpu_ms(s), d.cells[0], d.cells[1], d.cells[2], d.cell_size, d.voxels_per_cell,
        static_cast<unsigned long long>(s.refined), static_cast<unsigned long long>(s.coarsened), s.residual,
        quality_name(report.quality));
    const char* keys =
        report.touring
            ? "Tab panels  H hide  C stop the tour  drag orbit  wheel zoom  F follow  Q G W R T Y views"
            : "Tab panels  H hide  C tour  drag orbit  wheel zoom  F follow  Q G W R T Y views";
    // Wrapped at the frame's edge, so that small frames keep it all on two lines.
    const ImVec2 padding(6.0f, 3.0f);
    const float wrap = ImGui::GetIO().DisplaySize.x - 20.0f - 2.0f * padding.x;
    const ImVec2 text = report.windowed ? text_block({stats, keys}, wrap) : text_block({stats}, wrap);
    ImGui::SetNextWindowPos(ImVec2(6, 6));
    ImGui::SetNextWindowSize(ImVec2(text.x + 2.0f * padding.x, text.y + 2.0f * padding.y));
    ImGui::SetNextWindowBgAlpha(0.55f);
    ImGui::PushStyleVar(ImGuiStyleVar_WindowPadding, padding);
    ImGui::Begin("##stats", nullptr, kLabel);
    ImGui::PushTextWrapPos(padding.x + wrap);
    ImGui::TextUnformatted(stats);
    if (report.windowed) {
        ImGui::PushStyleColor(ImGuiCol_Text, ImGui::GetStyle().Colors[ImGuiCol_TextDisabled]);
        ImGui::TextUnformatted(keys);
        ImGui::PopStyleColor();
    }
    ImGui::PopTextWrapPos();
    ImGui::End();
    ImGui::PopStyleVar();
}

void draw_caption(const TourFrame& frame) {
    const ImVec2 display = ImGui::GetIO().DisplaySize;
    const ImVec2 padding = ImGui::GetStyle().WindowPadding;
    const float width = std::min(display.x - 16.0f, 720.0f);
    const float wrap = width - 2.0f * padding.x;
    char title[128];
    std::snprintf(title, sizeof(title), "%zu/%zu  %s", frame.index + 1, tour_shots().size(),
                  frame.shot->title);
    const ImVec2 text = text_block({title, frame.shot->caption}, wrap);
    ImGui::SetNextWindowPos(ImVec2(0.5f * display.x, display.y - 8.0f), ImGuiCond_Always, ImVec2(0.5f, 1.0f));
    ImGui::SetNextWindowSize(ImVec2(width, text.y + 2.0f * padding.y));
    ImGui::SetNextWindowBgAlpha(0.6f);
    ImGui::Begin("##caption", nullptr, kLabel);
    ImGui::PushTextWrapPos(padding.x + wrap);
    ImGui::TextColored(ImVec4(1.0f, 0.85f, 0.35f, 1.0f), "%s", title);
    ImGui::TextUnformatted(frame.shot->caption);
    ImGui::PopTextWrapPos();
    ImGui::End();
}

PanelActions draw_panels(const OverlayReport& report, const PanelControls& controls) {
    PanelActions actions;
    const gust::FrameStats& s = *report.stats;
    ImGui::SetNextWindowPos(ImVec2(6, 48), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.75f);
    ImGui::Begin("gust", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::Text("%.1f fps (%.1f ms a frame), quality %s", report.fps, report.frame_ms,
                quality_name(report.quality));
    ImGui::Text("gust: %.1f ms GPU, %u pressure iterations", gpu_ms(s), s.cycles);
    if (ImGui::CollapsingHeader("GPU ms per pass")) {
        for (const auto& [name, ms] : s.ms)
            ImGui::Text("%-18s %7.2f", name.c_str(), ms);
    }
    if (ImGui::CollapsingHeader("tree and memory", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Text("nodes %llu (+%llu refined, -%llu coarsened blocks)",
                    static_cast<unsigned long long>(s.nodes), static_cast<unsigned long long>(s.refined),
                    static_cast<unsigned long long>(s.coarsened));
        if (!controls.nodes_per_level.empty()) {
            std::string levels;
            for (const auto& [level, n] : controls.nodes_per_level)
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
        WorldSettings& w = controls.world;
        ImGui::SliderFloat("ambient m/s", &w.wind_speed, 0.0f, 12.0f);
        ImGui::SliderFloat("heading", &w.wind_heading_deg, -180.0f, 180.0f);
        ImGui::SliderFloat("gustiness", &w.gustiness, 0.0f, 1.0f);
        ImGui::Checkbox("fan", &w.fan_on);
        ImGui::SameLine();
        ImGui::SliderFloat("fan m/s", &w.fan_strength, 0.0f, 15.0f);
        ImGui::Checkbox("flyer's motor", &w.flyer_motor_on);
        ImGui::SliderFloat("walk speed", &w.walk_speed, 0.0f, 2.0f);
        int cells[3] = {static_cast<int>(controls.cells[0]), static_cast<int>(controls.cells[1]),
                        static_cast<int>(controls.cells[2])};
        if (ImGui::SliderInt3("cells", cells, 8, 128)) {
            for (int i = 0; i < 3; ++i)
                controls.cells[i] = static_cast<std::uint32_t>(cells[i]);
        }
        actions.apply_resolution = ImGui::Button("apply resolution");
    }
    if (ImGui::CollapsingHeader("views")) {
        Views& v = controls.views;
        bool changed = ImGui::Checkbox("Q triangles", &v.triangles);
        ImGui::SameLine();
        changed |= ImGui::Checkbox("G grass", &v.grass);
        changed |= ImGui::Checkbox("W voxels", &v.voxels);
        changed |= ImGui::Checkbox("R tree nodes (green made, grey kept, red freed)", &v.nodes);
        ImGui::SameLine();
        changed |= ImGui::Checkbox("every node", &v.every_node);
        changed |= ImGui::Checkbox("T wind slice", &v.slice);
        ImGui::SameLine();
        changed |= ImGui::Checkbox("Y arrows", &v.arrows);
        changed |= ImGui::SliderFloat("slice height", &v.slice_height, 0.1f, 8.0f);
        changed |= ImGui::Checkbox("F follow the fox", &controls.follow);
        ImGui::Text("E: one more tree level; drag: orbit; wheel: zoom; space: pause; C: tour; H: hide");
        actions.camera_or_views_changed = changed;
    }
    ImGui::End();
    return actions;
}

} // namespace sample
