// What every gust benchmark needs besides its measurements: wall-clock timing, the number formats of the
// results tables, asset loading, a description of the machine and the run, and the writer that puts a
// results block into docs/results.md.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <gust/gpu/context.hpp>
#include <gust/gpu/result.hpp>
#include <gust/scene/mesh.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace gust::bench {

/// The clock every timing uses: monotonic, so that a clock adjustment cannot distort a measurement.
using Clock = std::chrono::steady_clock;

/// Milliseconds since `start`, the unit every column uses.
double ms_since(Clock::time_point start);

/// Prints a fatal error as "<tool>: error: ..." the way the other gust tools do; gives the exit status.
int fail(std::string_view tool, const std::string& message);

/// Groups digits by thousands so that byte and voxel counts read at a glance.
std::string grouped(std::uint64_t n);

/// Formats milliseconds with about three significant digits.
std::string fmt_ms(double ms);

/// How many decimals fmt_ratio gives a ratio below 0.1 (two above it up to 10, one from 10 on).
enum class RatioBelowTenth {
    TwoDecimals,  ///< "0.05x", as the voxelize tables have always shown OpenVDB / gust
    ThreeDecimals ///< "0.050x", about three significant digits where small ratios are the point
};

/// Formats a size or time ratio as "<ratio>x", the unit the benches' goals are stated in.
std::string fmt_ratio(double ratio, RatioBelowTenth small = RatioBelowTenth::ThreeDecimals);

/// The path of an asset, or a message that says where it was looked for, so a missing file is obvious.
gust::Result<std::filesystem::path> asset_path(const std::filesystem::path& assets,
                                               const std::string& relative);

/// Loads a static mesh asset, failing with asset_path's message when it is missing.
gust::Result<gust::Mesh> load_asset(const std::filesystem::path& assets, const std::string& relative);

/// Cores this process may run on (what TBB and lavapipe share), not the machine's total.
int usable_cores();

/// The CPU model line of /proc/cpuinfo, since lavapipe's speed is the CPU's.
std::string cpu_model();

/// UTC date and time now, so that a results block says when it was measured.
std::string utc_now();

/// The 1-minute load average, since other processes on the same cores slow every column down.
std::string load_average();

/// What the run looked like from outside: how it was started, when, and how busy the machine was.
struct RunInfo {
    std::string command;
    std::string started;    ///< UTC
    std::string load_start; ///< 1-minute load average when the run started
    Clock::time_point start;
};

/// The command line as typed, so the block says how to reproduce it.
std::string command_line(int argc, char** argv);

/// A table cell for a failed measurement pointing at its note, so long messages stay out of the table.
std::string failed_cell(std::vector<std::string>& notes, const std::string& what, const std::string& error);

/// The results block a bench run writes: `bench` on a CPU-emulated device (lavapipe, what CI has), and
/// `bench`-gpu on a real one, so that docs/results.md keeps both and neither run overwrites the other.
std::string block_name(std::string_view bench, const gust::gpu::DeviceInfo& device);

/// What a block's heading adds after its title: nothing on a CPU device, " (on <device name>)" on a GPU.
std::string heading_device(const gust::gpu::DeviceInfo& device);

/// Replaces (or appends) the `<!-- bench:name:begin/end -->` block in `path`, leaving the rest byte for byte.
gust::Status write_block(const std::filesystem::path& path, std::string_view name, const std::string& body);

} // namespace gust::bench
