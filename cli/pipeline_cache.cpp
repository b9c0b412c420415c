#include "pipeline_cache.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <unistd.h>

namespace gust::cli {

namespace {

namespace fs = std::filesystem;

/// `folder`/gust/pipelines.bin when `folder` is an absolute path under which gust/ exists or can be
/// made, and can be written; empty otherwise.
std::string file_under(const char* folder) {
    if (!folder || !*folder) return {};
    const fs::path base(folder);
    // The XDG Base Directory specification: relative paths are invalid and must be ignored.
    if (!base.is_absolute()) return {};
    const fs::path dir = base / "gust";
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || access(dir.c_str(), W_OK) != 0) return {};
    return (dir / "pipelines.bin").string();
}

} // namespace

std::string pipeline_cache_file(bool disabled) {
    if (disabled) return {};
    if (const char* env = std::getenv("GUST_PIPELINE_CACHE"); env && *env)
        return std::string(env) == "off" ? std::string() : std::string(env);
    if (std::string file = file_under(std::getenv("XDG_CACHE_HOME")); !file.empty()) return file;
    const char* home = std::getenv("HOME");
    if (!home || !*home) return {};
    return file_under((fs::path(home) / ".cache").c_str());
}

} // namespace gust::cli
