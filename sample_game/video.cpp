#include "video.hpp"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <fcntl.h>
#include <spawn.h>
#include <string_view>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

extern char** environ;

namespace sample {

namespace {

/// Lossy at quality 60: the grass moves everywhere, so every frame is nearly a key frame, and lossless
/// frames of it are ten times the size for no visible gain at video speed.
constexpr const char* kQuality = "60";

} // namespace

std::filesystem::path find_on_path(const std::string& program) {
    const char* path = std::getenv("PATH");
    if (!path) return {};
    std::string_view rest(path);
    while (!rest.empty()) {
        const std::size_t colon = rest.find(':');
        const std::string_view dir = rest.substr(0, colon);
        rest = colon == std::string_view::npos ? std::string_view() : rest.substr(colon + 1);
        if (dir.empty()) continue;
        const std::filesystem::path candidate = std::filesystem::path(dir) / program;
        if (access(candidate.c_str(), X_OK) == 0) return candidate;
    }
    return {};
}

VideoOutcome write_animated_webp(std::span<const std::filesystem::path> frames, int frame_ms,
                                 const std::filesystem::path& out) {
    const std::filesystem::path encoder = find_on_path("img2webp");
    if (encoder.empty())
        return {false, "img2webp not found (Debian package webp): no " + out.filename().string() +
                           ", the PNG frames are all there"};
    std::vector<std::string> args = {encoder.string(), "-loop", "0", "-lossy", "-q",
                                     kQuality,         "-m",    "4", "-d",     std::to_string(frame_ms)};
    for (const std::filesystem::path& frame : frames)
        args.push_back(frame.string());
    args.push_back("-o");
    args.push_back(out.string());
    std::vector<char*> argv;
    for (std::string& a : args)
        argv.push_back(a.data());
    argv.push_back(nullptr);

    const std::string log = out.string() + ".log";
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    pid_t pid = 0;
    const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (spawned != 0) return {false, "cannot start " + encoder.string() + ": no " + out.filename().string()};
    int status = 0;
    while (waitpid(pid, &status, 0) < 0) {
        if (errno != EINTR) return {false, "lost " + encoder.string() + " while it ran"};
    }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !std::filesystem::exists(out))
        return {false,
                encoder.string() + " failed (its output is in " + log + "): no " + out.filename().string()};
    std::filesystem::remove(log);
    const double kib = static_cast<double>(std::filesystem::file_size(out)) / 1024.0;
    char line[256];
    std::snprintf(line, sizeof(line), "wrote %s (%zu frames, %.1f %s)", out.string().c_str(), frames.size(),
                  kib < 1024.0 ? kib : kib / 1024.0, kib < 1024.0 ? "KiB" : "MiB");
    return {true, line};
}

} // namespace sample
