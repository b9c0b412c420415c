// The sample game's loop: gust used as an engine uses it, on the game's own Vulkan device.
#pragma once

#include "quality.hpp"
#include "views.hpp"
#include "world.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>

namespace sample {

/// Everything the command line sets (docs/sample.md lists the flags).
struct GameOptions {
    bool headless = false;    ///< render offscreen even when a display exists
    std::uint32_t frames = 0; ///< stop after this many frames (0: windowed, until closed; headless, the tour)
    std::filesystem::path out; ///< PNG frames (headless), the animated WebP and stats.jsonl; empty: no files
    std::uint32_t png_every = 1; ///< headless: write every K-th frame's PNG
    std::uint32_t width = 960, height = 540;
    std::filesystem::path assets;    ///< the repository's assets/ folder
    bool validation = false;         ///< Khronos validation on the game's device; any message fails the run
    Quality quality = Quality::Auto; ///< detail preset (Auto: from the device type)
    DetailOverrides detail;          ///< the preset's values the command line replaced
    std::optional<float> dt;         ///< fixed time step (s); unset: 1/30 headless, the clock windowed
    Views views;                     ///< the views to start with (without the tour)
    bool tour = true;                ///< play the guided tour (windowed: until the camera is touched)
    bool follow = false;             ///< start with the camera following the fox
    /// The wind's focus and the camera fly a loop over the valley (World::flight_at), so that every
    /// cascade scrolls: the long run of docs/sample.md, "A flight across the world".
    bool fly = false;
    bool hud = true;     ///< start with the overlay shown (H toggles it)
    bool video = true;   ///< headless: encode the PNG frames into an animated WebP as well
    WorldSettings world; ///< its grass_blades are the preset's (or --grass)
};

/// Runs the game; returns the process exit code (0: fine). Prints what went wrong on stderr.
int run_game(const GameOptions& options);

} // namespace sample
