// The sample game's loop: gust used as an engine uses it, on the game's own Vulkan device.
#pragma once

#include "renderer.hpp"
#include "world.hpp"

#include <cstdint>
#include <filesystem>
#include <string>

namespace sample {

/// Everything the command line sets (docs/sample.md lists the flags).
struct GameOptions {
    bool headless = false;       ///< render offscreen even when a display exists
    std::uint32_t frames = 0;    ///< stop after this many frames (0: until the window closes)
    std::filesystem::path out;   ///< PNG frames (headless) and stats.jsonl; empty: no files
    std::uint32_t png_every = 1; ///< headless: write every K-th frame's PNG
    std::uint32_t width = 960, height = 540;
    std::filesystem::path assets; ///< the repository's assets/ folder
    bool validation = false;      ///< Khronos validation on the game's device; any message fails the run
    std::uint32_t wind_cells[3] = {16, 8, 16};
    float cell_size = 1.75f; ///< m
    std::uint32_t voxels_per_cell = 2;
    std::uint32_t max_cycles = 4; ///< pressure iterations per frame (the field carries over)
    float dt = 1.0f / 30.0f;      ///< headless: fixed time step (s); windowed runs use the clock
    Views views;
    bool follow = false; ///< start with the camera following the fox
    bool hud = true;     ///< start with the HUD shown (H toggles it)
    WorldSettings world;
};

/// Runs the game; returns the process exit code (0: fine). Prints what went wrong on stderr.
int run_game(const GameOptions& options);

} // namespace sample
