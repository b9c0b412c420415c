// Measures what one `gust voxelize` call costs, as a user runs it (one process per call, pipeline cache
// and all), beside OpenVDB's mesh-to-volume on the same triangles and grid, taken in turn on the same
// cores. Optionally another build of the command (`--baseline`) runs in the same rounds, so that a
// change is measured before and after side by side.
#include "bench_common.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <gust/scene/mesh.hpp>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <tbb/task_arena.h>
#include <vector>

namespace {

using gust::bench::Clock;
using gust::bench::fmt_ms;
using gust::bench::fmt_ratio;
using gust::bench::ms_since;

constexpr const char* kTool = "gust_bench_cli";
/// Names this bench's block in the results file (`<!-- bench:voxelize-cli:begin -->`).
constexpr const char* kBlock = "voxelize-cli";
/// The stages `gust voxelize` times, in its order.
constexpr std::array<const char*, 7> kStages = {"import",   "device", "upload", "voxelize",
                                                "readback", "unique", "write"};

int fail(const std::string& message) {
    return gust::bench::fail(kTool, message);
}

struct Options {
    std::filesystem::path assets = GUST_ASSETS_DIR;
    std::string mesh = "scans/dragon_res2.ply";
    std::uint32_t res = 512;
    std::vector<std::string> methods = {"auto", "compute", "raster"};
    int runs = 5;
    std::string cli = GUST_CLI_PATH;
    std::string baseline;                   ///< another `gust` binary measured in the same rounds
    std::string baseline_name = "baseline"; ///< what the tables call it (the commit it was built from)
    std::string write;
};

/// Quotes a word for /bin/sh.
std::string shell_word(const std::string& word) {
    std::string out = "'";
    for (char c : word)
        out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

/// Runs `command` through the shell; its stdout, or an error naming the command.
gust::Result<std::string> run(const std::string& command) {
    FILE* pipe = popen((command + " 2>/dev/null").c_str(), "r");
    if (!pipe) return gust::Result<std::string>::failure("cannot run " + command);
    std::string out;
    std::array<char, 4096> buffer;
    while (std::size_t n = std::fread(buffer.data(), 1, buffer.size(), pipe))
        out.append(buffer.data(), n);
    const int status = pclose(pipe);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return gust::Result<std::string>::failure(command + " failed");
    return out;
}

/// One binary with one --method, over the rounds.
struct Series {
    std::string binary; ///< "this build" or Options::baseline_name
    std::string path;
    std::string method;
    std::vector<double> process_ms;                   ///< wall-clock of the whole process
    std::map<std::string, std::vector<double>> stage; ///< the stats line's ms per stage
    std::vector<double> gpu_ms;                       ///< the stats line's gpu_ms summed
    std::string used;                                 ///< the path it reported
    std::string cache;                                ///< "read", "written" or "off"
    nlohmann::json last;                              ///< the last stats line
};

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double best(const std::vector<double>& v) {
    return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end());
}

/// One `gust voxelize` process, timed from outside.
gust::Status measure(Series& s, const std::string& mesh, const Options& options, const std::string& out) {
    const std::string command = shell_word(s.path) + " voxelize " + shell_word(mesh) + " --res " +
                                std::to_string(options.res) + " --method " + s.method + " --out " +
                                shell_word(out);
    const auto start = Clock::now();
    auto stdout_text = run(command);
    const double ms = ms_since(start);
    if (!stdout_text) return stdout_text.status();
    nlohmann::json line;
    try {
        line = nlohmann::json::parse(*stdout_text);
    } catch (const nlohmann::json::exception& e) {
        return gust::Status::failure(command + ": its stats line is not JSON (" + e.what() + ")");
    }
    s.process_ms.push_back(ms);
    for (const char* stage : kStages)
        if (line["ms"].contains(stage)) s.stage[stage].push_back(line["ms"][stage].get<double>());
    double gpu = 0.0;
    for (const auto& [pass, t] : line["gpu_ms"].items())
        gpu += t.get<double>();
    s.gpu_ms.push_back(gpu);
    s.used = line.value("method", "");
    if (!line.contains("pipeline_cache"))
        s.cache = "none (older build)";
    else if (line["pipeline_cache"].is_null())
        s.cache = "off";
    else
        s.cache = line["pipeline_cache"]["loaded"].get<bool>() ? "read" : "written";
    s.last = line;
    return {};
}

/// OpenVDB's unsigned distance field with a one-voxel band on the grid the stats line states, as
/// gust_bench_voxelize times it.
gust::Result<double> time_openvdb(const gust::Mesh& mesh, const nlohmann::json& grid) {
    try {
        const double h = grid["voxel_size"].get<double>();
        auto transform = openvdb::math::Transform::createLinearTransform(h);
        transform->postTranslate(openvdb::Vec3d(grid["origin"][0].get<double>() + 0.5 * h,
                                                grid["origin"][1].get<double>() + 0.5 * h,
                                                grid["origin"][2].get<double>() + 0.5 * h));
        std::vector<openvdb::Vec3s> points;
        points.reserve(mesh.positions.size());
        for (const glm::vec3& p : mesh.positions)
            points.emplace_back(p.x, p.y, p.z);
        std::vector<openvdb::Vec3I> triangles;
        for (std::size_t t = 0; t + 2 < mesh.indices.size(); t += 3)
            triangles.emplace_back(mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]);
        const std::vector<openvdb::Vec4I> quads;
        const auto start = Clock::now();
        auto sdf = openvdb::tools::meshToUnsignedDistanceField<openvdb::FloatGrid>(*transform, points,
                                                                                   triangles, quads, 1.0f);
        const double ms = ms_since(start);
        if (!sdf || sdf->activeVoxelCount() == 0)
            return gust::Result<double>::failure("OpenVDB gave an empty grid");
        return ms;
    } catch (const std::exception& e) {
        return gust::Result<double>::failure(std::string("OpenVDB: ") + e.what());
    }
}

std::string render(const std::vector<Series>& series, const std::vector<double>& vdb, const Options& options,
                   const nlohmann::json& info, const gust::bench::RunInfo& run_info,
                   std::uint64_t triangles) {
    std::ostringstream out;
    const double vdb_ms = median(vdb);
    out << "## `gust voxelize` as one command, against OpenVDB"
        << (info.value("device_type", "") == "cpu" ? std::string()
                                                   : " (on " + info.value("device", std::string()) + ")")
        << "\n\n";
    out << "Command: `" << run_info.command << "`\n\n";
    out << "Machine: Vulkan device " << info.value("device", "?") << " (" << info.value("device_type", "?")
        << ", " << info.value("driver", "?") << "); CPU " << gust::bench::cpu_model() << ", "
        << gust::bench::usable_cores() << " usable cores, TBB arena of "
        << tbb::this_task_arena::max_concurrency() << " threads. Run started " << run_info.started
        << " and took " << fmt_ms(ms_since(run_info.start) / 60000.0) << " min; 1-minute load average "
        << run_info.load_start << " at the start and " << gust::bench::load_average()
        << " at the end (a load above the core count means other processes shared the cores).\n\n";
    out << "`" << options.mesh << "` (" << gust::bench::grouped(triangles) << " triangles) at " << options.res
        << "^3 on the grid `gust voxelize` picks (its bounding box made cubic and padded by one voxel). "
        << options.runs
        << " rounds; each round runs every command below once, as its own process, then OpenVDB's "
           "`tools::meshToUnsignedDistanceField<FloatGrid>` with a one-voxel band on the same triangles and "
           "grid in this process (as `gust_bench_voxelize` does). Times are medians over the rounds (best in "
           "brackets). *voxelize* is the stats line's `ms.voxelize` (wall-clock around the voxelizer's call, "
           "which includes choosing the path); *process* is the command's whole run as the shell sees it "
           "(start, import, device, pipelines, voxelize, readback, write). The pipeline cache column says "
           "whether the runs read the file a previous run wrote.\n\n";
    out << "| Build | `--method` | Path used | Pipeline cache | voxelize ms | GPU ms | process ms | "
           "OpenVDB ms | OpenVDB / voxelize | OpenVDB / process |\n";
    out << "|---|---|---|---|--:|--:|--:|--:|--:|--:|\n";
    for (const Series& s : series) {
        const std::vector<double>& v = s.stage.at("voxelize");
        out << "| " << s.binary << " | " << s.method << " | " << s.used << " | " << s.cache << " | "
            << fmt_ms(median(v)) << " (" << fmt_ms(best(v)) << ") | " << fmt_ms(median(s.gpu_ms)) << " | "
            << fmt_ms(median(s.process_ms)) << " (" << fmt_ms(best(s.process_ms)) << ") | " << fmt_ms(vdb_ms)
            << " (" << fmt_ms(best(vdb)) << ") | " << fmt_ratio(vdb_ms / median(v)) << " | "
            << fmt_ratio(vdb_ms / median(s.process_ms)) << " |\n";
    }
    out << "\nWhere a process's time goes: medians of the stats line's stages, ms (the process column less "
           "their "
           "sum is starting the process, loading libraries, and tearing down).\n\n";
    out << "| Build | `--method` |";
    for (const char* stage : kStages)
        out << " " << stage << " |";
    out << " process |\n|---|---|";
    for (std::size_t i = 0; i <= kStages.size(); ++i)
        out << "--:|";
    out << "\n";
    for (const Series& s : series) {
        out << "| " << s.binary << " | " << s.method << " |";
        for (const char* stage : kStages) {
            const auto it = s.stage.find(stage);
            out << " " << (it == s.stage.end() ? std::string("-") : fmt_ms(median(it->second))) << " |";
        }
        out << " " << fmt_ms(median(s.process_ms)) << " |\n";
    }
    return out.str();
}

} // namespace

int main(int argc, char** argv) {
    Options options;
    CLI::App app{"Times `gust voxelize` as one command per call beside OpenVDB's mesh-to-volume on the same "
                 "triangles, grid and cores"};
    app.add_option("--assets", options.assets, "gust's assets folder")->check(CLI::ExistingDirectory);
    app.add_option("--mesh", options.mesh, "mesh under the assets folder");
    app.add_option("--res", options.res, "grid resolution")->check(CLI::Range(8, 1024));
    app.add_option("--methods", options.methods, "--method values to run, comma separated")->delimiter(',');
    app.add_option("--runs", options.runs, "rounds (medians are reported)")->check(CLI::Range(1, 1000));
    app.add_option("--cli", options.cli, "the gust binary to measure");
    app.add_option("--baseline", options.baseline, "another gust binary run in the same rounds");
    app.add_option("--baseline-name", options.baseline_name,
                   "what the tables call the baseline, e.g. the commit it was built from");
    app.add_option("--write", options.write,
                   "Markdown file whose voxelize-cli block is replaced (or appended)");
    CLI11_PARSE(app, argc, argv);
    const gust::bench::RunInfo run_info{gust::bench::command_line(argc, argv), gust::bench::utc_now(),
                                        gust::bench::load_average(), Clock::now()};
    openvdb::initialize();

    auto mesh_path = gust::bench::asset_path(options.assets, options.mesh);
    if (!mesh_path) return fail(mesh_path.message());
    auto mesh = gust::bench::load_asset(options.assets, options.mesh);
    if (!mesh) return fail(mesh.message());
    auto info_text = run(shell_word(options.cli) + " info");
    if (!info_text) return fail(info_text.message());
    const nlohmann::json info = nlohmann::json::parse(*info_text, nullptr, false);
    if (info.is_discarded()) return fail(options.cli + " info: its output is not JSON");

    std::vector<Series> series;
    for (const std::string& method : options.methods) {
        series.push_back({"this build", options.cli, method, {}, {}, {}, {}, {}, {}});
        if (!options.baseline.empty())
            series.push_back({options.baseline_name, options.baseline, method, {}, {}, {}, {}, {}, {}});
    }
    const std::string out = (std::filesystem::temp_directory_path() / "gust_bench_cli.vdb").string();
    std::vector<double> vdb;
    for (int round = 0; round < options.runs; ++round) {
        for (Series& s : series)
            if (gust::Status st = measure(s, mesh_path->string(), options, out); !st)
                return fail(st.message());
        auto ms = time_openvdb(*mesh, series.front().last);
        if (!ms) return fail(ms.message());
        vdb.push_back(*ms);
        std::cerr << "round " << round + 1 << ":";
        for (const Series& s : series)
            std::cerr << " " << s.binary << " " << s.method << " " << fmt_ms(s.stage.at("voxelize").back())
                      << "/" << fmt_ms(s.process_ms.back()) << " ms;";
        std::cerr << " OpenVDB " << fmt_ms(*ms) << " ms" << std::endl;
    }
    std::filesystem::remove(out);

    const std::string body = render(series, vdb, options, info, run_info, mesh->triangle_count());
    std::cout << body << std::flush;
    if (!options.write.empty()) {
        const std::string name =
            info.value("device_type", "") == "cpu" ? kBlock : std::string(kBlock) + "-gpu";
        if (gust::Status s = gust::bench::write_block(options.write, name, body); !s)
            return fail(s.message());
        std::cerr << "wrote the " << name << " block of " << options.write << "\n";
    }
    return 0;
}
