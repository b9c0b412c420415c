// What the sample draws over the scene with Dear ImGui: a one-line stats bar, the tour's caption and, one
// key away, the full panels.
#pragma once

#include "quality.hpp"
#include "tour.hpp"
#include "views.hpp"
#include "world.hpp"

#include <array>
#include <cstdint>
#include <gust/gust.hpp>
#include <map>

namespace sample {

/// What the overlay reports this frame.
struct OverlayReport {
    double fps = 0.0;                        ///< frames per second since the first frame
    double frame_ms = 0.0;                   ///< the last frame, ms
    const gust::FrameStats* stats = nullptr; ///< gust's last step
    gust::WindDomain domain;                 ///< the System's domain
    Quality quality = Quality::Low;          ///< the resolved preset
    bool windowed = false;                   ///< a person is at the keys: show them
    bool touring = false;                    ///< the tour directs the camera
};

/// The stats bar: one line at the top left (and, in a window, one line of keys).
void draw_stats_bar(const OverlayReport& report);

/// The shot's title and caption at the bottom of the frame.
void draw_caption(const TourFrame& frame);

/// What the full panels may change.
struct PanelControls {
    WorldSettings& world;
    Views& views;
    bool& follow;                                                  ///< camera follows the fox
    std::array<std::uint32_t, 3>& cells;                           ///< applied on request
    const std::map<std::uint32_t, std::uint64_t>& nodes_per_level; ///< from the R view's download
};

/// What the person did in the panels this frame.
struct PanelActions {
    bool camera_or_views_changed = false; ///< a view or follow was toggled (the tour then stops)
    bool apply_resolution = false;        ///< re-create the System with `cells`
};

/// The full panels: GPU time per pass, tree and memory, wind controls and views.
PanelActions draw_panels(const OverlayReport& report, const PanelControls& controls);

} // namespace sample
