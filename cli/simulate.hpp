// `gust simulate`: runs a scene file headless and writes per-frame stats and OpenVDB frames.
#pragma once

#include <cstdint>
#include <string>

namespace gust::cli {

/// Options of `gust simulate` (docs/design.md "Interfaces").
struct SimulateArgs {
    std::string scene;        ///< scene file (JSON)
    std::uint32_t frames = 0; ///< frames to run, >= 1
    std::string out;          ///< output folder (created)
    std::uint32_t every = 0;  ///< write frame 0 and every K-th frame after it; 0: frame 0 only
    std::string method = "auto";
    std::string device;
    bool validation = false;
    bool no_pipeline_cache = false; ///< run without the pipeline cache file (pipeline_cache.hpp)
};

/// Runs the command; returns the process exit code, printing errors to stderr.
int run_simulate(const SimulateArgs& args);

} // namespace gust::cli
