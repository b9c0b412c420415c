// gust_sample: animated characters and props moving through wind over a field of grass (docs/sample.md).
#include "game.hpp"

#include <CLI/CLI.hpp>
#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char** argv) {
    sample::GameOptions options;
    options.assets = GUST_SAMPLE_ASSETS;
    CLI::App app{"gust sample game: wind through grass, trees and walking characters"};
    std::string out, assets = options.assets.string(), views;
    std::vector<std::uint32_t> cells;
    float cell_size = 0.0f, dt = 0.0f;
    std::uint32_t voxels_per_cell = 0, grass = 0, max_iterations = 0, cascades = 0;
    app.add_flag("--headless", options.headless,
                 "render offscreen and write PNG frames (also without a display)");
    app.add_option("--frames", options.frames, "stop after N frames (headless default: the tour's length)");
    app.add_option("--out", out,
                   "folder for PNG frames, the animated WebP and stats.jsonl (headless default out/sample)");
    app.add_option("--png-every", options.png_every, "headless: write every K-th frame's PNG")
        ->check(CLI::Range(1u, 1000000u));
    app.add_option("--width", options.width, "frame width in pixels")->check(CLI::Range(64u, 8192u));
    app.add_option("--height", options.height, "frame height in pixels")->check(CLI::Range(64u, 8192u));
    std::string quality = "auto";
    app.add_option("--quality", quality,
                   "detail preset: auto (from the device type), low, medium or high (docs/sample.md)")
        ->check(CLI::IsMember({"auto", "low", "medium", "high"}, CLI::ignore_case));
    CLI::Option* grass_option = app.add_option("--grass", grass, "grass blades (default: the preset's)")
                                    ->check(CLI::Range(0u, 2000000u));
    app.add_option("--wind", options.world.wind_speed, "ambient wind speed, m/s")
        ->check(CLI::Range(0.0f, 60.0f));
    app.add_option("--wind-heading", options.world.wind_heading_deg,
                   "ambient wind direction, degrees from +x about +y")
        ->check(CLI::Range(-360.0f, 360.0f));
    app.add_option("--gustiness", options.world.gustiness, "relative size of the gusts")
        ->check(CLI::Range(0.0f, 1.0f));
    bool no_fan = false, no_motor = false, no_hud = false, no_tour = false, no_video = false;
    app.add_flag("--no-hud", no_hud, "start with the HUD and captions hidden");
    app.add_flag("--no-fan", no_fan, "switch the fan off");
    app.add_flag("--no-motor", no_motor, "switch the flyer's motor off");
    app.add_flag("--no-tour", no_tour,
                 "no guided tour: a slowly circling camera (headless) or yours (windowed)");
    app.add_flag("--no-video", no_video, "headless: write no animated WebP of the frames");
    CLI::Option* cells_option =
        app.add_option("--cells", cells, "wind cells X,Y,Z, each 8..256 (default: the preset's)")
            ->delimiter(',')
            ->expected(3)
            ->check(CLI::Range(8u, 256u));
    CLI::Option* cell_size_option =
        app.add_option("--cell-size", cell_size, "wind cell edge, m (default: the preset's)")
            ->check(CLI::Range(0.05f, 20.0f));
    CLI::Option* voxels_option =
        app.add_option("--voxels-per-cell", voxels_per_cell,
                       "voxels per wind cell per axis: 1, 2, 4 or 8 (default: the preset's)")
            ->check(CLI::IsMember({1u, 2u, 4u, 8u}));
    CLI::Option* iterations_option = app.add_option("--max-iterations", max_iterations,
                                                    "pressure iterations per frame (default: the preset's)")
                                         ->check(CLI::Range(1u, 200u));
    CLI::Option* cascades_option =
        app.add_option(
               "--cascades", cascades,
               "nested wind grids around the village, each 4 times coarser, 1..4 (default: the preset's)")
            ->check(CLI::Range(1u, sample::kMaxCascades));
    CLI::Option* dt_option =
        app.add_option("--dt", dt, "fixed time step, s (default 1/30 headless; windowed: the clock)")
            ->check(CLI::Range(0.001f, 0.5f));
    CLI::Option* views_option =
        app.add_option("--views", views,
                       "views to start with: any of q (hide triangles), g (hide grass), w, r, t, y (no tour)")
            ->check(CLI::Validator(
                [](const std::string& letters) {
                    const std::size_t bad = letters.find_first_not_of("qgwrty,");
                    return bad == std::string::npos
                               ? std::string()
                               : "takes letters from 'qgwrty', got '" + letters.substr(bad, 1) + "'";
                },
                "LETTERS"));
    CLI::Option* follow_option = app.add_flag("--follow", options.follow, "camera follows the fox (no tour)");
    CLI::Option* fly_option = app.add_flag(
        "--fly", options.fly, "the wind's focus and the camera fly a loop over the valley (no tour)");
    app.add_flag("--validation", options.validation, "Khronos validation on; any message fails the run");
    app.add_option("--assets", assets, "the repository's assets/ folder");
    CLI11_PARSE(app, argc, argv);

    for (char v : views) {
        switch (v) {
        case 'q':
            options.views.triangles = false;
            break;
        case 'g':
            options.views.grass = false;
            break;
        case 'w':
            options.views.voxels = true;
            break;
        case 'r':
            options.views.nodes = true;
            break;
        case 't':
            options.views.slice = true;
            break;
        case 'y':
            options.views.arrows = true;
            break;
        default: // ',' (the validator above lets nothing else through)
            break;
        }
    }
    options.quality = *sample::parse_quality(quality);
    if (cells_option->count()) options.detail.cells = {{cells[0], cells[1], cells[2]}};
    if (cell_size_option->count()) options.detail.cell_size = cell_size;
    if (voxels_option->count()) options.detail.voxels_per_cell = voxels_per_cell;
    if (grass_option->count()) options.detail.grass_blades = grass;
    if (iterations_option->count()) options.detail.max_cycles = max_iterations;
    if (cascades_option->count()) options.detail.cascades = cascades;
    if (dt_option->count()) options.dt = dt;
    // Asking for views or the follow camera is asking for a camera of one's own.
    options.tour = !no_tour && !views_option->count() && !follow_option->count() && !fly_option->count();
    options.hud = !no_hud;
    options.video = !no_video;
    options.world.fan_on = !no_fan;
    options.world.flyer_motor_on = !no_motor;
    options.assets = assets;
    options.out = out;
    return sample::run_game(options);
}
