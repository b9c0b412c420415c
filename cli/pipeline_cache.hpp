// Where the `gust` command keeps its Vulkan pipeline cache between runs (docs/cli.md, "Pipeline cache").
#pragma once

#include <string>

namespace gust::cli {

/// The pipeline cache file for this run: $GUST_PIPELINE_CACHE when set (a file path, or "off" for none),
/// else gust/pipelines.bin under $XDG_CACHE_HOME (when it is an absolute path) or else under
/// $HOME/.cache, whichever folder can be written first. Empty, meaning no file, when `disabled`
/// (--no-pipeline-cache), when the variable says "off", or when no folder can be written.
std::string pipeline_cache_file(bool disabled);

} // namespace gust::cli
