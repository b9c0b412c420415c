// The sample's guided tour: a short film of shots that each show one thing gust does (docs/sample.md).
#pragma once

#include "camera.hpp"
#include "stage.hpp"
#include "views.hpp"

#include <cstddef>
#include <span>

namespace sample {

/// One shot: what it shows and how it is filmed.
struct Shot {
    const char* key;     ///< short name, as stats.jsonl's `shot` writes it
    const char* title;   ///< a few words
    const char* caption; ///< one sentence: what to look at
    float seconds;       ///< tour time the shot lasts
    /// Frames the shot at `u` (0 at its start, 1 at its end) on this frame's stage.
    void (*direct)(const Stage& stage, float u, OrbitCamera& camera, Views& views);
};

/// The tour at one moment.
struct TourFrame {
    std::size_t index = 0; ///< of the shot, from 0
    const Shot* shot = nullptr;
    OrbitCamera camera;
    Views views;
};

/// The shots in order.
std::span<const Shot> tour_shots();
/// The whole tour, s.
double tour_seconds();
/// The shot and camera `t` seconds into the tour (past its end it starts again).
TourFrame tour_at(double t, const Stage& stage);

} // namespace sample
