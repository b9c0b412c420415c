// The sample game's binary: headless frames, foliage that follows the wind, the tour and its animated WebP,
// the quality presets, and windowed runs under Xvfb (a person at the keys included).
#include <algorithm>
#include <cmath>
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

/// The shot of each stats line, in order ("" where a line has none).
std::vector<std::string> shots_of(const std::vector<nlohmann::json>& stats) {
    std::vector<std::string> shots;
    for (const nlohmann::json& line : stats)
        shots.push_back(line.value("shot", std::string()));
    return shots;
}

/// The shots in the order they first appear.
std::vector<std::string> distinct_in_order(const std::vector<std::string>& shots) {
    std::vector<std::string> out;
    for (const std::string& s : shots)
        if (out.empty() || out.back() != s) out.push_back(s);
    return out;
}

/// The shots docs/sample.md lists, in order.
const std::vector<std::string> kShots = {"overview", "grass", "fan",    "wake",
                                         "tree",     "field", "valley", "lee"};

/// RGB pixels of a PNG (empty when it cannot be read).
std::vector<unsigned char> load_rgb(const fs::path& file, int& w, int& h) {
    int channels = 0;
    unsigned char* pixels = stbi_load(file.c_str(), &w, &h, &channels, 3);
    if (!pixels) return {};
    std::vector<unsigned char> rgb(pixels, pixels + std::size_t(w) * h * 3);
    stbi_image_free(pixels);
    return rgb;
}

/// The fraction of pixels whose colour differs by more than 40 (of 255) in some channel.
double changed_fraction(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
    if (a.size() != b.size() || a.empty()) return 0.0;
    std::size_t changed = 0;
    for (std::size_t p = 0; p < a.size(); p += 3)
        for (std::size_t c = 0; c < 3; ++c)
            if (std::abs(int(a[p + c]) - int(b[p + c])) > 40) {
                ++changed;
                break;
            }
    return static_cast<double>(changed) / static_cast<double>(a.size() / 3);
}

/// The first bytes of a file.
std::string head_of(const fs::path& file, std::size_t bytes) {
    std::ifstream in(file, std::ios::binary);
    std::string head(bytes, '\0');
    in.read(head.data(), static_cast<std::streamsize>(bytes));
    head.resize(static_cast<std::size_t>(in.gcount()));
    return head;
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

TEST(SampleGame, theFlightCarriesEveryCascadeAcrossTheValleyAndTheWindStaysBounded) {
    // --fly: the focus loops 300 m round the village at 12 m/s over the terrain, so at dt 0.1 s the finest
    // cascade (cells of 1.75 m) scrolls every step and the coarsest (28 m) every few. Every solve
    // converges and no blade passes its cap; the domain follows the flight up and down the slopes.
    const fs::path dir = fresh_dir("fly");
    const Outcome r =
        run("--headless --fly --frames 24 --dt 0.1 --png-every 100 --out " + dir.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<nlohmann::json> stats = read_stats(dir / "stats.jsonl");
    ASSERT_EQ(stats.size(), 24u);
    const auto origin = [&](std::size_t i, int a) { return stats[i]["domain_origin"][a].get<double>(); };
    // 23 steps of 1.2 m along the loop: about 28 m, all but a cell of it along z at the start (x = 300 m).
    EXPECT_NEAR(origin(23, 2) - origin(0, 2), 27.6, 2.0);
    EXPECT_NEAR(origin(0, 0), 300.0 - 8.0 * 1.75, 2.0);
    for (const nlohmann::json& line : stats) {
        EXPECT_TRUE(line["converged"].get<bool>()) << line.dump();
        EXPECT_FALSE(line["diverged"].get<bool>()) << line.dump();
        EXPECT_LE(line["grass_bend_max"].get<double>(), 1.2) << line.dump();
    }
    fs::remove_all(dir);
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
    // and the mean bend must follow it, under the low preset's three cascades too (docs/sample.md, "Gusts
    // under three cascades"); 3 m/s keeps the blades below their 1.2 cap.
    const fs::path dir = fresh_dir("gusts");
    const Outcome r = run("--headless --frames 80 --dt 0.1 --png-every 1000 --wind 3 --gustiness 1 --no-fan "
                          "--no-motor --out " +
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

TEST(SampleGame, theDefaultHeadlessRunIsTheTourWithACaptionedShotPerLineAndAnAnimatedWebp) {
    // At 0.5 s a frame the 21.5 s tour is 43 frames; its PNGs are written every frame and encoded with
    // img2webp (scripts/install_deps.sh installs webp).
    const fs::path out = fresh_dir("tour");
    const Outcome r = run("--headless --dt 0.5 --out " + out.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<nlohmann::json> stats = read_stats(out / "stats.jsonl");
    ASSERT_EQ(stats.size(), 43u);
    const std::vector<std::string> shots = shots_of(stats);
    EXPECT_EQ(distinct_in_order(shots), kShots);
    for (const nlohmann::json& line : stats) {
        const std::string shot = line.value("shot", "");
        const std::string views = line["views"].get<std::string>();
        const std::string expected = shot == "tree"     ? "qgwr"
                                     : shot == "field"  ? "ty"
                                     : shot == "valley" ? "gt"
                                                        : views;
        EXPECT_EQ(views, expected) << shot << " at frame " << line["frame"];
    }

    // The ridge shelters its lee: by the lee shot the crowns there bend less than those on its crest.
    for (const nlohmann::json& line : stats) {
        if (line.value("shot", "") != "lee") continue;
        EXPECT_LT(line["lee_bend"].get<double>(), 0.7 * line["crest_bend"].get<double>())
            << "at frame " << line["frame"];
    }

    // Each cut moves the camera and changes the picture: the first frame of a shot against the last frame
    // of the one before. The valley's green slopes fill the background of the village's shots where the sky
    // did, so the cut from the overview to the grass changes 14% of the pixels (measured), the others over
    // 20%.
    for (std::size_t f = 1; f < shots.size(); ++f) {
        if (shots[f] == shots[f - 1]) continue;
        const std::vector<double> eye_before = stats[f - 1]["eye"], eye_after = stats[f]["eye"];
        const double jump = std::hypot(eye_after[0] - eye_before[0], eye_after[1] - eye_before[1],
                                       eye_after[2] - eye_before[2]);
        EXPECT_GT(jump, 2.0) << "the camera hardly moves from " << shots[f - 1] << " to " << shots[f];
        char before[32], after[32];
        std::snprintf(before, sizeof(before), "frame_%04zu.png", f - 1);
        std::snprintf(after, sizeof(after), "frame_%04zu.png", f);
        int w = 0, h = 0;
        const std::vector<unsigned char> a = load_rgb(out / before, w, h), b = load_rgb(out / after, w, h);
        ASSERT_FALSE(a.empty() || b.empty()) << before << " or " << after;
        EXPECT_GT(changed_fraction(a, b), 0.1) << "the cut from " << shots[f - 1] << " to " << shots[f];
    }

    const std::string webp = head_of(out / "tour.webp", 64);
    ASSERT_EQ(webp.size(), 64u) << r.output;
    EXPECT_EQ(webp.substr(0, 4), "RIFF");
    EXPECT_EQ(webp.substr(8, 4), "WEBP");
    EXPECT_NE(webp.find("ANIM"), std::string::npos) << "not an animated WebP";
    EXPECT_NE(r.output.find("tour.webp (43 frames"), std::string::npos) << r.output;
    fs::remove_all(out);
}

TEST(SampleGame, aRunLongerThanTheTourKeepsEveryFrameButMakesAVideoOfOnePass) {
    // 50 frames of 0.5 s: every PNG is written, the WebP shows the tour's 21.5 s once (43 frames).
    const fs::path out = fresh_dir("long_run");
    const Outcome r = run("--headless --dt 0.5 --frames 50 --out " + out.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_TRUE(fs::exists(out / "frame_0049.png"));
    EXPECT_NE(r.output.find("tour.webp (43 frames"), std::string::npos) << r.output;
    fs::remove_all(out);
}

TEST(SampleGame, withoutTheEncoderTheRunStillSucceedsAndSaysSo) {
    const fs::path out = fresh_dir("no_encoder");
    const fs::path empty_path = fresh_dir("empty_path");
    fs::create_directories(empty_path);
    const Outcome r = run_command("env PATH=" + empty_path.string() + " " + std::string(GUST_SAMPLE_BINARY) +
                                  " --headless --frames 3 --out " + out.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("img2webp not found"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out / "tour.webp"));
    EXPECT_TRUE(fs::exists(out / "frame_0002.png"));
    fs::remove_all(out);
    fs::remove_all(empty_path);
}

TEST(SampleGame, aQualityPresetSetsTheGridAndFlagsOverrideSingleValues) {
    // docs/sample.md's table: medium is 32x12x32 cells of 1 m, 4 voxels per cell, 8 iterations; high is
    // 0.5 m cells, 4 voxels per cell, 16 iterations. --grass (kSmall) and --cells override the preset.
    const fs::path medium_dir = fresh_dir("medium"), high_dir = fresh_dir("high");
    const std::string common = " --headless --frames 1 --no-video" + kSmall;
    const Outcome medium = run("--quality medium --out " + medium_dir.string() + common);
    const Outcome high = run("--quality high --cells 16,8,16 --out " + high_dir.string() + common);
    ASSERT_EQ(medium.exit_code, 0) << medium.output;
    ASSERT_EQ(high.exit_code, 0) << high.output;
    const nlohmann::json m = read_stats(medium_dir / "stats.jsonl").at(0);
    EXPECT_EQ(m["quality"], "medium");
    EXPECT_EQ(m["cells"], nlohmann::json({32, 12, 32}));
    EXPECT_DOUBLE_EQ(m["cell_size"].get<double>(), 1.0);
    EXPECT_EQ(m["voxels_per_cell"], 4);
    EXPECT_EQ(m["max_iterations"], 8);
    EXPECT_EQ(m["grass"], 3000);
    const nlohmann::json h = read_stats(high_dir / "stats.jsonl").at(0);
    EXPECT_EQ(h["quality"], "high");
    EXPECT_EQ(h["cells"], nlohmann::json({16, 8, 16}));
    EXPECT_DOUBLE_EQ(h["cell_size"].get<double>(), 0.5);
    EXPECT_EQ(h["max_iterations"], 16);
    EXPECT_NE(medium.output.find("quality medium: 32x12x32 cells of 1.00 m"), std::string::npos)
        << medium.output;
    fs::remove_all(medium_dir);
    fs::remove_all(high_dir);
}

TEST(SampleGame, autoQualityFollowsTheDeviceType) {
    // docs/sample.md: a CPU device gets low, a discrete GPU high, anything else medium.
    const fs::path out = fresh_dir("auto");
    const Outcome r = run("--headless --frames 1 --no-video --out " + out.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string expected = r.output.find("a CPU device") != std::string::npos     ? "low"
                                 : r.output.find("a discrete GPU") != std::string::npos ? "high"
                                                                                        : "medium";
    EXPECT_NE(r.output.find("quality " + expected + " (auto)"), std::string::npos) << r.output;
    EXPECT_EQ(read_stats(out / "stats.jsonl").at(0)["quality"], expected);
    fs::remove_all(out);
}

// --views checked its letters itself and exited 2, where every other bad flag gives CLI11's code.
TEST(SampleGame, badFlagsFailWithOneExitCodeAndTheirReasonBeforeAnythingStarts) {
    const Outcome views = run("--headless --views qx");
    const Outcome png = run("--headless --png-every 0");
    EXPECT_NE(views.exit_code, 0);
    EXPECT_EQ(views.exit_code, png.exit_code) << views.output << png.output;
    EXPECT_NE(views.output.find("takes letters from 'qgwrty', got 'x'"), std::string::npos) << views.output;
    EXPECT_NE(png.output.find("not in range 1 to"), std::string::npos) << png.output;
    for (const Outcome* r : {&views, &png})
        EXPECT_EQ(r->output.find("headless on"), std::string::npos)
            << "the device was created: " << r->output;
}

TEST(SampleGame, anUnknownQualityIsAClearErrorBeforeAnythingStarts) {
    const Outcome r = run("--headless --quality ultra");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find("--quality: ultra not in {auto,low,medium,high}"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("headless on"), std::string::npos) << "the device was created: " << r.output;
}

TEST(SampleGame, theWindowedTourUnderXvfbPlaysEveryShotAndExitsCleanly) {
    const fs::path out = fresh_dir("windowed_tour");
    const Outcome r =
        run_command("xvfb-run -a -s \"-screen 0 640x480x24\" " + std::string(GUST_SAMPLE_BINARY) +
                    " --frames 43 --dt 0.5 --out " + out.string() + kSmall);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("windowed"), std::string::npos) << r.output;
    EXPECT_EQ(distinct_in_order(shots_of(read_stats(out / "stats.jsonl"))), kShots);
    fs::remove_all(out);
}

TEST(SampleGame, aPersonAtTheWindowTakesTheCameraFromTheTourAndCGivesItBack) {
    // Under Xvfb, xdotool drags across the window (the tour stops), presses F and W (follow the fox, voxels
    // on), then C (the tour again) and Esc (quit). After each step the script waits until the game has
    // written five more frames to stats.jsonl (the test fails after a minute without them), so a slow or
    // busy machine still sees every step land in its own frames.
    const fs::path out = fresh_dir("person");
    const std::string stats_file = (out / "stats.jsonl").string();
    const std::string game =
        std::string(GUST_SAMPLE_BINARY) + " --frames 3000 --dt 0.1 --out " + out.string() + kSmall;
    const std::string script = "frames() { cat " + stats_file +
                               " 2>/dev/null | wc -l; }; "
                               "advance() { n=$(frames); i=0; while [ $(frames) -lt $((n + 5)) ]; do "
                               "[ $i -lt 600 ] || { echo no new frames for a minute; kill $game; exit 1; }; "
                               "sleep 0.1; i=$((i + 1)); done; }; " +
                               game +
                               " & game=$!; "
                               "win=$(xdotool search --sync --name \"gust sample\"); "
                               "xdotool mousemove --window $win 96 54; advance; "
                               "xdotool mousedown 1 mousemove_relative 30 10 mouseup 1; advance; "
                               "xdotool key f key w; advance; "
                               "xdotool key c; advance; "
                               "xdotool key Escape; wait $game";
    // Single quotes: the script's variables belong to the shell inside xvfb-run, which has the display.
    const Outcome r = run_command("xvfb-run -a -s \"-screen 0 640x480x24\" sh -c '" + script + "'");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::vector<nlohmann::json> stats = read_stats(out / "stats.jsonl");
    ASSERT_FALSE(stats.empty()) << r.output;
    EXPECT_LT(stats.size(), 3000u) << "Esc did not end the run";
    EXPECT_TRUE(stats.front().contains("shot")) << "the tour plays from the start";
    // The phases in order: touring; taken over (no shot) with the views the tour left, then with the fox
    // followed and W's voxels toggled; touring again.
    bool taken = false, followed = false, back = false;
    std::string left;
    for (const nlohmann::json& line : stats) {
        if (!line.contains("shot")) {
            if (!taken) left = line["views"];
            taken = true;
            std::string toggled;
            for (char v : std::string("qgwrty"))
                if ((left.find(v) != std::string::npos) != (v == 'w')) toggled += v;
            if (line["follow"] == true && line["views"] == toggled) followed = true;
        } else if (taken) {
            back = true;
        }
    }
    EXPECT_TRUE(taken) << "dragging did not stop the tour";
    EXPECT_TRUE(followed) << "F and W did not follow the fox and show the voxels";
    EXPECT_TRUE(back) << "C did not play the tour again";
    fs::remove_all(out);
}
