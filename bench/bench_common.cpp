#include "bench_common.hpp"

#include <cstdio>
#include <ctime>
#include <fstream>
#include <gust/scene/import.hpp>
#include <iostream>
#include <iterator>
#include <sched.h>

namespace gust::bench {

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

int fail(std::string_view tool, const std::string& message) {
    std::cerr << tool << ": error: " << message << "\n";
    return 1;
}

std::string grouped(std::uint64_t n) {
    const std::string digits = std::to_string(n);
    std::string out;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i && (digits.size() - i) % 3 == 0) out += ',';
        out += digits[i];
    }
    return out;
}

std::string fmt_ms(double ms) {
    char text[32];
    std::snprintf(text, sizeof(text), ms < 10.0 ? "%.2f" : ms < 1000.0 ? "%.1f" : "%.0f", ms);
    return text;
}

std::string fmt_ratio(double ratio, RatioBelowTenth small) {
    char text[32];
    const char* format = ratio < 0.1 && small == RatioBelowTenth::ThreeDecimals ? "%.3fx"
                         : ratio < 10.0                                         ? "%.2fx"
                                                                                : "%.1fx";
    std::snprintf(text, sizeof(text), format, ratio);
    return text;
}

gust::Result<std::filesystem::path> asset_path(const std::filesystem::path& assets,
                                               const std::string& relative) {
    const std::filesystem::path path = assets / relative;
    if (!std::filesystem::exists(path))
        return gust::Result<std::filesystem::path>::failure(
            "asset not found: " + path.string() + " (pass --assets DIR to point at gust's assets folder)");
    return path;
}

gust::Result<gust::Mesh> load_asset(const std::filesystem::path& assets, const std::string& relative) {
    auto path = asset_path(assets, relative);
    if (!path) return path.status();
    return gust::load_mesh(*path);
}

int usable_cores() {
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof(set), &set) != 0) return 0;
    return CPU_COUNT(&set);
}

std::string cpu_model() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) return line.substr(line.find_first_not_of(" \t", colon + 1));
        }
    return "unknown";
}

std::string utc_now() {
    const std::time_t now = std::time(nullptr);
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[64];
    std::strftime(text, sizeof(text), "%Y-%m-%d %H:%M UTC", &tm);
    return text;
}

std::string load_average() {
    std::ifstream in("/proc/loadavg");
    std::string first;
    return in >> first ? first : std::string("unknown");
}

std::string command_line(int argc, char** argv) {
    std::string line;
    for (int i = 0; i < argc; ++i) {
        if (i) line += ' ';
        const std::string arg = argv[i];
        line += arg.find_first_of(" \t'\"") == std::string::npos ? arg : "'" + arg + "'";
    }
    return line;
}

std::string failed_cell(std::vector<std::string>& notes, const std::string& what, const std::string& error) {
    notes.push_back(what + ": " + error);
    return "failed (note " + std::to_string(notes.size()) + ")";
}

std::string block_name(std::string_view bench, const gust::gpu::DeviceInfo& device) {
    return device.type == "cpu" ? std::string(bench) : std::string(bench) + "-gpu";
}

std::string heading_device(const gust::gpu::DeviceInfo& device) {
    return device.type == "cpu" ? std::string() : " (on " + std::string(device.name) + ")";
}

gust::Status write_block(const std::filesystem::path& path, std::string_view name, const std::string& body) {
    const std::string begin_marker = "<!-- bench:" + std::string(name) + ":begin -->";
    const std::string end_marker = "<!-- bench:" + std::string(name) + ":end -->";
    std::string text;
    if (std::filesystem::exists(path)) {
        std::ifstream in(path, std::ios::binary);
        if (!in) return gust::Status::failure(path.string() + ": cannot read");
        text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    const std::string block = begin_marker + "\n" + body + end_marker;
    const auto begin = text.find(begin_marker);
    const auto end = begin == std::string::npos ? std::string::npos : text.find(end_marker, begin);
    if (begin != std::string::npos && end == std::string::npos)
        return gust::Status::failure(path.string() + ": has " + begin_marker + " but no " + end_marker +
                                     " after it");
    if (begin != std::string::npos) {
        text.replace(begin, end + end_marker.size() - begin, block);
    } else {
        if (!text.empty()) text += text.back() == '\n' ? "\n" : "\n\n";
        text += block + "\n";
    }
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    if (!out) return gust::Status::failure(path.string() + ": cannot write");
    out << text;
    out.close();
    if (!out) return gust::Status::failure(path.string() + ": write failed");
    return {};
}

} // namespace gust::bench
