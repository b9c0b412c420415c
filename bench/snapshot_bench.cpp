// Times System::sample (one thread, CPU) beside System::query (a blocking GPU round trip), and a step with
// the snapshot against one without, interleaved in one run (docs/api.md "Wind snapshot").
//   gust_bench_snapshot [points] [--no-steps]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <gust/gust.hpp>
#include <memory>
#include <random>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

std::unique_ptr<gust::System> make(std::uint32_t x, std::uint32_t y, std::uint32_t z, bool snapshot) {
    gust::SystemDesc desc;
    desc.domain.cells[0] = x;
    desc.domain.cells[1] = y;
    desc.domain.cells[2] = z;
    desc.snapshot = snapshot;
    std::unique_ptr<gust::System> system;
    if (const gust::Outcome o = gust::System::create(desc, system); !o) {
        std::fprintf(stderr, "create: %s\n", o.message().c_str());
        std::exit(1);
    }
    system->set_ambient({3.0f, 0.0f, 1.0f});
    return system;
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

} // namespace

int main(int argc, char** argv) {
    const std::size_t count = argc > 1 ? std::size_t(std::atol(argv[1])) : 1000000;
    auto system = make(32, 16, 32, true);
    system->step(1.0f / 60.0f);
    std::mt19937 random(1);
    std::uniform_real_distribution<float> x(-17.0f, 17.0f), y(-1.0f, 17.0f);
    std::vector<gust::Vec3> points(count), out(count);
    for (gust::Vec3& p : points)
        p = {x(random), y(random), x(random)};
    std::vector<double> sample_s, query_s;
    for (int r = 0; r < 5; ++r) {
        auto start = Clock::now();
        if (!system->sample(points, out)) return 1;
        sample_s.push_back(seconds_since(start));
        start = Clock::now();
        if (!system->query(points, out)) return 1;
        query_s.push_back(seconds_since(start));
    }
    std::printf("device: %s\n", system->device_name());
    std::printf("sample, one thread: %zu points in %.2f ms, %.1f M points/s\n", count, median(sample_s) * 1e3,
                double(count) / median(sample_s) / 1e6);
    std::printf("query (blocking):   %zu points in %.2f ms, %.1f M points/s\n", count, median(query_s) * 1e3,
                double(count) / median(query_s) / 1e6);
    const gust::Vec3 one[1] = {{0.0f, 4.0f, 0.0f}};
    gust::Vec3 one_out[1];
    std::vector<double> one_sample, one_query;
    for (int r = 0; r < 21; ++r) {
        auto start = Clock::now();
        system->sample(one, one_out);
        one_sample.push_back(seconds_since(start));
        start = Clock::now();
        system->query(one, one_out);
        one_query.push_back(seconds_since(start));
    }
    std::printf("one point: sample %.2f us, query %.2f us\n", median(one_sample) * 1e6,
                median(one_query) * 1e6);
    system.reset();
    if (argc > 2 && std::string(argv[2]) == "--no-steps") return 0;

    const std::uint32_t sizes[2][3] = {{32, 16, 32}, {64, 64, 64}};
    for (const auto& n : sizes) {
        auto without = make(n[0], n[1], n[2], false), with = make(n[0], n[1], n[2], true);
        for (int w = 0; w < 3; ++w) {
            without->step(1.0f / 60.0f);
            with->step(1.0f / 60.0f);
        }
        std::vector<double> a, b;
        for (int r = 0; r < 15; ++r) {
            auto start = Clock::now();
            without->step(1.0f / 60.0f);
            a.push_back(seconds_since(start));
            start = Clock::now();
            with->step(1.0f / 60.0f);
            b.push_back(seconds_since(start));
        }
        std::printf(
            "%ux%ux%u step: %.2f ms without the snapshot, %.2f ms with (%+.1f %%), 15 interleaved each\n",
            n[0], n[1], n[2], median(a) * 1e3, median(b) * 1e3, (median(b) / median(a) - 1.0) * 100.0);
    }
    return 0;
}
