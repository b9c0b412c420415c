// Helpers shared by the scene test suites: small glTF files built in memory and per-test folders.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <glm/glm.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <unistd.h>
#include <vector>

namespace gust::test {

using nlohmann::json;

inline std::string base64(const std::vector<unsigned char>& bytes) {
    static constexpr char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < bytes.size(); i += 3) {
        const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
        std::uint32_t v = 0;
        for (std::size_t k = 0; k < 3; ++k)
            v = (v << 8) | (k < n ? bytes[i + k] : 0u);
        for (std::size_t k = 0; k < 4; ++k) {
            out += k <= n ? kDigits[(v >> (18 - 6 * k)) & 63u] : '=';
        }
    }
    return out;
}

/// Builds small glTF files with one embedded buffer.
class GltfWriter {
  public:
    GltfWriter() {
        doc_ = {{"asset", {{"version", "2.0"}}},
                {"scenes", json::array({json::object({{"nodes", json::array()}})})},
                {"nodes", json::array()},
                {"meshes", json::array()},
                {"accessors", json::array()},
                {"bufferViews", json::array()}};
    }

    int add_view(const void* data, std::size_t size) {
        while (bin_.size() % 4 != 0)
            bin_.push_back(0);
        const std::size_t offset = bin_.size();
        bin_.resize(offset + size);
        std::memcpy(bin_.data() + offset, data, size);
        doc_["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}});
        return static_cast<int>(doc_["bufferViews"].size()) - 1;
    }

    /// An accessor over `data` with glTF `component_type` (5126 float, 5123 unsigned short, ...) and
    /// `type` ("SCALAR", "VEC3", "MAT4", ...); `extra` adds members such as "normalized".
    template <class T>
    int add_data(const std::vector<T>& data, int component_type, const char* type,
                 json extra = json::object()) {
        const int view = add_view(data.data(), data.size() * sizeof(T));
        const std::size_t components = std::string(type) == "SCALAR" ? 1
                                       : std::string(type) == "MAT4" ? 16
                                                                     : std::string(type).back() - '0';
        const std::size_t component_size = component_type == 5126 || component_type == 5125   ? 4
                                           : component_type == 5122 || component_type == 5123 ? 2
                                                                                              : 1;
        json accessor = {{"bufferView", view},
                         {"componentType", component_type},
                         {"count", data.size() * sizeof(T) / (components * component_size)},
                         {"type", type}};
        accessor.update(extra);
        return add_accessor(std::move(accessor));
    }

    int add_positions(const std::vector<glm::vec3>& positions) { return add_data(positions, 5126, "VEC3"); }

    int add_indices(const std::vector<std::uint16_t>& indices) { return add_data(indices, 5123, "SCALAR"); }

    int add_accessor(json accessor) {
        doc_["accessors"].push_back(std::move(accessor));
        return static_cast<int>(doc_["accessors"].size()) - 1;
    }

    int add_mesh(json primitives) {
        doc_["meshes"].push_back({{"primitives", std::move(primitives)}});
        return static_cast<int>(doc_["meshes"].size()) - 1;
    }

    int add_node(json node) {
        doc_["nodes"].push_back(std::move(node));
        return static_cast<int>(doc_["nodes"].size()) - 1;
    }

    void add_root(int node) { doc_["scenes"][0]["nodes"].push_back(node); }

    json& doc() { return doc_; }

    std::string text() {
        json doc = doc_;
        doc["buffers"] = json::array(
            {{{"byteLength", bin_.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin_)}}});
        return doc.dump();
    }

  private:
    json doc_;
    std::vector<unsigned char> bin_;
};

inline const std::vector<glm::vec3> kTriangle = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

inline json triangle_primitive(int positions) {
    return json::array({{{"attributes", {{"POSITION", positions}}}}});
}

/// A fresh folder, removed with everything in it when this goes out of scope.
class TempDir {
  public:
    TempDir() {
        static std::atomic<int> counter{0};
        path_ = std::filesystem::temp_directory_path() /
                ("gust_scene_tmp_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    const std::filesystem::path& path() const { return path_; }

    /// Writes `contents` to `name` inside the folder and returns the file's path.
    std::filesystem::path write(const std::string& name, const std::string& contents) const {
        const std::filesystem::path file = path_ / name;
        std::filesystem::create_directories(file.parent_path());
        std::ofstream(file, std::ios::binary) << contents;
        return file;
    }

  private:
    std::filesystem::path path_;
};

// docs/design.md, "Interfaces that others rely on", verbatim: this core must keep reading as written.
inline constexpr const char* kDesignExample = R"({
  "dt": 0.02,
  "domain": { "center": [0, 8, 0], "cells": [32, 16, 32], "cell_size": 1.0,
              "voxels_per_cell": 4, "branching": 4 },
  "ambient": { "velocity": [4, 0, 0] },
  "objects": [
    { "mesh": "wall.obj", "static": true,
      "transform": { "translate": [0, 0, 0], "rotate_deg": [0, 30, 0], "scale": 1.0 } },
    { "mesh": "bunny.ply", "keyframes": [
        { "t": 0.0, "translate": [-10, 2, 0], "rotate_deg": [0, 0, 0], "scale": 1.0 },
        { "t": 2.0, "translate": [ 10, 2, 0], "rotate_deg": [0, 180, 0], "scale": 1.0 } ] }
  ],
  "emitters": [ { "type": "omni", "position": [0, 2, 5], "radius": 3, "strength": 8 } ]
})";

} // namespace gust::test
