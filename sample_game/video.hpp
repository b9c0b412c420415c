// The headless run's frames as one animated image a browser opens, made by an encoder found at run time.
#pragma once

#include <filesystem>
#include <span>
#include <string>

namespace sample {

/// Where `program` is on PATH; empty when it is nowhere there.
std::filesystem::path find_on_path(const std::string& program);

/// What became of the animated image.
struct VideoOutcome {
    bool written = false; ///< `out` exists and holds every frame
    std::string message;  ///< one line for the log: what was written, or why not
};

/// Encodes `frames` (PNG files, in order, each shown for `frame_ms`) into a looping animated WebP at `out`
/// with img2webp (Debian package `webp`). Without img2webp on PATH nothing is written and the message says
/// so; the encoder's own output goes to `out` with ".log" appended, kept only when it fails.
VideoOutcome write_animated_webp(std::span<const std::filesystem::path> frames, int frame_ms,
                                 const std::filesystem::path& out);

} // namespace sample
