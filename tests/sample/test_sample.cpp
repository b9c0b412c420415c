// The sample game's binary: headless frames, foliage that follows the wind, and a windowed run under Xvfb.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <set>
#include <stb/stb_image.h>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

/// A small, fast configuration: lavapipe renders and simulates it in a few seconds.
const std::string kSmall = " --width 192 --height 108 --grass 3000 --validation";

struct Outcome {
    int exit_code = -1;
    std::string output;
};

/// Runs a shell command, collecting its stdout and stderr.
Outcome run_command(const std::string& command) {
    Outcome r;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return r;
    char buffer[512];
    while (std::fgets(buffer, sizeof(buffer), pipe))
        r.output += buffer;
    const int status = pclose(pipe);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

/// Runs the sample with `arguments`.
Outcome run(const std::string& arguments) {
    return run_command(std::string(GUST_SAMPLE_BINARY) + " " + arguments);
}

fs::path fresh_dir(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("gust_sample_test_" + name);
    fs::remove_all(dir);
    return dir;
}

std::vector<nlohmann::json> read_stats(const fs::path& file) {
    std::vector<nlohmann::json> lines;
    std::ifstream in(file);
    for (std::string line; std::getline(in, line);)
        lines.push_back(nlohmann::json::parse(line));
    return lines;
}

double mean_bend_over(const std::vector<nlohmann::json>& stats, std::size_t first) {
    double sum = 0.0;
    for (std::size_t i = first; i < stats.size(); ++i)
        sum += stats[i]["grass_bend_mean"].get<double>();
    return stats.size() > first ? sum / static_cast<double>(stats.size() - first) : 0.0;
}

} // namespace

TEST(SampleGame, headlessRunWritesNonEmptyFramesAndStats) {
    const fs::path out = fresh_dir("headless");
    const Outcome r = run("--headless --frames 4 --out " + out.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("fps"), std::string::npos) << r.output;
    for (int frame = 0; frame < 4; ++frame) {
        char name[32];
        std::snprintf(name, sizeof(name), "frame_%04d.png", frame);
        int w = 0, h = 0, channels = 0;
        unsigned char* pixels = stbi_load((out / name).c_str(), &w, &h, &channels, 3);
        ASSERT_NE(pixels, nullptr) << name << " is missing or not a PNG";
        EXPECT_EQ(w, 192);
        EXPECT_EQ(h, 108);
        // A rendered scene (sky, grass, buildings, HUD) has many colours; a blank or cleared frame has one.
        std::set<int> colours;
        for (int i = 0; i < w * h; ++i)
            colours.insert(pixels[3 * i] << 16 | pixels[3 * i + 1] << 8 | pixels[3 * i + 2]);
        stbi_image_free(pixels);
        EXPECT_GT(colours.size(), 200u) << name;
    }
    const std::vector<nlohmann::json> stats = read_stats(out / "stats.jsonl");
    ASSERT_EQ(stats.size(), 4u);
    EXPECT_GT(stats.back()["voxels"].get<std::uint64_t>(), 0u);
    EXPECT_GT(stats.back()["nodes"].get<std::uint64_t>(), 1u);
    fs::remove_all(out);
}

TEST(SampleGame, grassBendsWithTheWindAndStandsInCalm) {
    // Same scene twice: calm (no ambient wind, fan or motor) and a steady 8 m/s breeze. Walking characters
    // still push some air in the calm run, so it is compared with the windy one rather than with zero.
    const fs::path calm_dir = fresh_dir("calm"), windy_dir = fresh_dir("windy");
    const std::string common = " --headless --frames 24 --png-every 100" + kSmall;
    const Outcome calm =
        run("--wind 0 --gustiness 0 --no-fan --no-motor --out " + calm_dir.string() + common);
    const Outcome windy = run("--wind 8 --gustiness 0 --out " + windy_dir.string() + common);
    ASSERT_EQ(calm.exit_code, 0) << calm.output;
    ASSERT_EQ(windy.exit_code, 0) << windy.output;
    const double calm_bend = mean_bend_over(read_stats(calm_dir / "stats.jsonl"), 12);
    const double windy_bend = mean_bend_over(read_stats(windy_dir / "stats.jsonl"), 12);
    // A blade's steady bend is drag * |w|^2 = 0.025 * 64 = 1.6, capped at 1.2, where the wind is free;
    // shelter behind buildings lowers the mean, but not below a quarter.
    EXPECT_GT(windy_bend, 0.3);
    EXPECT_LT(calm_bend, 0.1 * windy_bend);
    fs::remove_all(calm_dir);
    fs::remove_all(windy_dir);
}

TEST(SampleGame, gustsMakeTheGrassSway) {
    // With gusts on, the ambient speed swings between about 1 and 6 m/s over eight seconds (World::ambient)
    // and the mean bend must follow it; 3 m/s keeps the blades below their 1.2 cap.
    const fs::path dir = fresh_dir("gusts");
    const Outcome r = run(
        "--headless --frames 80 --dt 0.1 --png-every 1000 --wind 3 --gustiness 1 --no-fan --no-motor --out " +
        dir.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<nlohmann::json> stats = read_stats(dir / "stats.jsonl");
    ASSERT_EQ(stats.size(), 80u);
    double lowest = 1e9, highest = 0.0;
    for (std::size_t i = 20; i < stats.size(); ++i) {
        lowest = std::min(lowest, stats[i]["grass_bend_mean"].get<double>());
        highest = std::max(highest, stats[i]["grass_bend_mean"].get<double>());
    }
    EXPECT_GT(highest, 1.5 * lowest) << "lowest " << lowest << ", highest " << highest;
    fs::remove_all(dir);
}

TEST(SampleGame, windowedRunUnderXvfbStartsRendersAndExitsCleanly) {
    const Outcome r = run_command("xvfb-run -a -s \"-screen 0 640x480x24\" " +
                                  std::string(GUST_SAMPLE_BINARY) + " --frames 5" + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("windowed"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("5 frames"), std::string::npos) << r.output;
}
