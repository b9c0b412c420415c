// Scene file loading. The JSON is parsed with a SAX handler rather than json::parse so that duplicate
// keys (which json::parse silently resolves to the last) are reported, and every error has a position.
// The checks below throw a private exception that load_scene turns into a Result: each check names
// its key path, and no exception leaves this file.
#include "gust/scene/scene_file.hpp"

#include "gust/scene/domain_grid.hpp"
#include "import_detail.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <initializer_list>
#include <limits>
#include <new>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace gust {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Scene files are hand-written or generated descriptions, never bulk data.
constexpr std::uintmax_t kMaxFileBytes = 64u << 20;
// Deeper nesting than any scene needs; the limit keeps recursive JSON copies and frees shallow.
constexpr std::size_t kMaxDepth = 64;
// Terrain limits: lengths and heights within 100 km (far beyond any domain, well inside a float's
// metre precision), a mesh of at most 8 million triangles (about 150 MB of positions and indices), and
// few enough features that every vertex sums them quickly.
constexpr double kMaxTerrainLength = 100000.0;
constexpr std::uint32_t kMaxTerrainSamples = 2048;
constexpr std::uint64_t kMaxTerrainTriangles = 8000000;
constexpr std::size_t kMaxTerrainFeatures = 64;

/// A failed check: "<key path>: <reason>" (load_scene adds the file).
struct Invalid {
    std::string message;
};

[[noreturn]] void fail(const std::string& at, const std::string& reason) {
    throw Invalid{(at.empty() ? std::string("(top level)") : at) + ": " + reason};
}

std::string key_path(const std::string& at, std::string_view key) {
    return at.empty() ? std::string(key) : at + "." + std::string(key);
}

std::string index_path(const std::string& at, std::size_t index) {
    return at + "[" + std::to_string(index) + "]";
}

/// Shortest text that reads back as `value`, with ".0" on whole numbers so they read as numbers.
/// The shortest text that reads back as `value` (float or double), with ".0" on whole numbers.
template <class Real> std::string format(Real value) {
    std::array<char, 32> buffer{};
    const auto [end, error] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
    std::string text = error == std::errc{} ? std::string(buffer.data(), end) : std::to_string(value);
    if (std::isfinite(value) && text.find_first_of(".e") == std::string::npos) text += ".0";
    return text;
}

std::string lower(std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
}

// ---------------------------------------------------------------------------------------------------
// Parsing

/// Builds the document like json::parse, but stops at a duplicate key or excessive nesting, and keeps
/// the byte position of a syntax error.
class DocumentBuilder {
  public:
    json& root() { return root_; }
    /// Empty, or "<key path>: <reason>" for a duplicate key or nesting, or the parser's reason.
    const std::string& error() const { return error_; }
    /// Byte position of a syntax error (1-based index of the last character read); 0 for other errors.
    std::size_t error_position() const { return error_position_; }

    bool null() { return add(json(nullptr)); }
    bool boolean(bool value) { return add(json(value)); }
    bool number_integer(json::number_integer_t value) { return add(json(value)); }
    bool number_unsigned(json::number_unsigned_t value) { return add(json(value)); }
    bool number_float(json::number_float_t value, const json::string_t&) { return add(json(value)); }
    bool string(json::string_t& value) { return add(json(std::move(value))); }
    bool binary(json::binary_t& value) { return add(json(std::move(value))); }
    bool start_object(std::size_t) { return open(json::object()); }
    bool start_array(std::size_t) { return open(json::array()); }
    bool end_object() { return close(); }
    bool end_array() { return close(); }

    bool key(json::string_t& name) {
        if (stack_.back().value->contains(name)) {
            error_ = key_path(stack_.back().path, name) + ": duplicate key";
            return false;
        }
        key_ = std::move(name);
        return true;
    }

    bool parse_error(std::size_t position, const std::string&, const json::exception& e) {
        error_position_ = position;
        std::string_view reason = e.what();
        // "[json.exception.parse_error.101] parse error at line 2, column 7: syntax error ..."
        if (reason.starts_with('[')) reason.remove_prefix(std::min(reason.size(), reason.find("] ") + 2));
        if (reason.starts_with("parse error"))
            reason.remove_prefix(std::min(reason.size(), reason.find(": ") + 2));
        error_ = detail::clean_message(reason);
        return false;
    }

  private:
    struct Open {
        json* value;
        std::string path;
    };

    /// Where the next value goes, and its key path.
    std::pair<json*, std::string> place(json value) {
        if (stack_.empty()) {
            root_ = std::move(value);
            return {&root_, ""};
        }
        Open& parent = stack_.back();
        if (parent.value->is_array()) {
            parent.value->push_back(std::move(value));
            return {&parent.value->back(), index_path(parent.path, parent.value->size() - 1)};
        }
        json& slot = (*parent.value)[key_];
        slot = std::move(value);
        return {&slot, key_path(parent.path, key_)};
    }

    bool add(json value) {
        place(std::move(value));
        return true;
    }

    bool open(json container) {
        auto [value, path] = place(std::move(container));
        if (stack_.size() >= kMaxDepth) {
            error_ = path + ": nested deeper than " + std::to_string(kMaxDepth) + " levels";
            return false;
        }
        // Pointers stay valid: a container is only added to while it is the innermost open one.
        stack_.push_back({value, std::move(path)});
        return true;
    }

    bool close() {
        stack_.pop_back();
        return true;
    }

    json root_;
    std::vector<Open> stack_;
    std::string key_;
    std::string error_;
    std::size_t error_position_ = 0;
};

/// "line L, column C" of the 1-based byte `position` in `text`.
std::string line_and_column(std::string_view text, std::size_t position) {
    const std::size_t index = std::min(position == 0 ? 0 : position - 1, text.size());
    const std::string_view before = text.substr(0, index);
    const auto line = 1 + std::count(before.begin(), before.end(), '\n');
    const std::size_t line_start = before.rfind('\n');
    const std::size_t column = line_start == std::string_view::npos ? index + 1 : index - line_start;
    return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

json parse_document(const fs::path& file) {
    std::error_code ec;
    const fs::file_status status = fs::status(file, ec);
    if (!fs::exists(status)) {
        if (ec && ec != std::errc::no_such_file_or_directory)
            throw Invalid{"cannot access file (" + ec.message() + ")"};
        throw Invalid{"file not found"};
    }
    if (fs::is_directory(status)) throw Invalid{"is a directory, not a scene file"};
    if (!fs::is_regular_file(status)) throw Invalid{"not a regular file"};
    const std::uintmax_t size = fs::file_size(file, ec);
    if (ec) throw Invalid{"cannot read file size (" + ec.message() + ")"};
    if (size == 0) throw Invalid{"empty file"};
    if (size > kMaxFileBytes) {
        throw Invalid{"file too large for a scene file (" + std::to_string(size) + " bytes, at most " +
                      std::to_string(kMaxFileBytes) + ")"};
    }
    std::ifstream in(file, std::ios::binary);
    if (!in) throw Invalid{"cannot open file for reading"};
    std::string text(static_cast<std::size_t>(size), '\0');
    in.read(text.data(), static_cast<std::streamsize>(text.size()));
    if (static_cast<std::size_t>(in.gcount()) != text.size()) throw Invalid{"cannot read file"};

    DocumentBuilder builder;
    if (!json::sax_parse(text, &builder, json::input_format_t::json, true)) {
        if (builder.error_position() != 0) {
            throw Invalid{"malformed JSON at " + line_and_column(text, builder.error_position()) + ": " +
                          builder.error()};
        }
        throw Invalid{builder.error()};
    }
    return std::move(builder.root());
}

// ---------------------------------------------------------------------------------------------------
// Checked values

const json& object(const json& value, const std::string& at) {
    if (!value.is_object()) fail(at, std::string("expected an object (found ") + value.type_name() + ")");
    return value;
}

const json& array(const json& value, const std::string& at) {
    if (!value.is_array()) fail(at, std::string("expected an array (found ") + value.type_name() + ")");
    return value;
}

/// Fails on the first key of `value` that is not in `keys`.
void allow_keys(const json& value, const std::string& at, std::initializer_list<std::string_view> keys) {
    for (const auto& [key, item] : value.items()) {
        if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
        std::string expected;
        for (std::string_view k : keys)
            expected += (expected.empty() ? "" : ", ") + std::string(k);
        fail(key_path(at, key), "unknown key (expected one of: " + expected + ")");
    }
}

/// The member `key` of object `value`, or null when absent.
const json* member(const json& value, std::string_view key) {
    const auto it = value.find(key);
    return it == value.end() ? nullptr : &*it;
}

const json& required(const json& value, std::string_view key, const std::string& at) {
    const json* item = member(value, key);
    if (item == nullptr) fail(key_path(at, key), "missing required key");
    return *item;
}

double number(const json& value, const std::string& at) {
    if (!value.is_number()) fail(at, std::string("expected a number (found ") + value.type_name() + ")");
    const double v = value.get<double>();
    if (!std::isfinite(v)) fail(at, "must be finite (found " + format(v) + ")");
    return v;
}

float to_float(double value, const std::string& at) {
    if (std::abs(value) > std::numeric_limits<float>::max()) {
        fail(at, "number " + format(value) + " is too large for a 32-bit float");
    }
    return static_cast<float>(value);
}

float float_number(const json& value, const std::string& at) {
    return to_float(number(value, at), at);
}

/// Fails unless `value` (> 0) stays a normal float: 1e-300 would reach the solver as 0.
void require_normal_float(double value, const std::string& at) {
    if (!(static_cast<float>(value) >= std::numeric_limits<float>::min()))
        fail(at, "number " + format(value) + " is too small for a 32-bit float (at least 1.2e-38)");
}

float positive_float(const json& value, const std::string& at) {
    const double exact = number(value, at);
    const float v = to_float(exact, at);
    if (exact > 0.0) require_normal_float(exact, at);
    if (!(v > 0.0f)) fail(at, "must be greater than 0 (found " + format(exact) + ")");
    return v;
}

std::uint32_t integer(const json& value, const std::string& at, std::uint32_t min, std::uint32_t max) {
    const double v = number(value, at);
    if (std::floor(v) != v || v < min || v > max) {
        fail(at, "must be an integer from " + std::to_string(min) + " to " + std::to_string(max) +
                     " (found " + format(v) + ")");
    }
    return static_cast<std::uint32_t>(v);
}

bool boolean(const json& value, const std::string& at) {
    if (!value.is_boolean())
        fail(at, std::string("expected true or false (found ") + value.type_name() + ")");
    return value.get<bool>();
}

std::string text(const json& value, const std::string& at) {
    if (!value.is_string()) fail(at, std::string("expected a string (found ") + value.type_name() + ")");
    std::string s = value.get<std::string>();
    if (s.empty()) fail(at, "must not be empty");
    return s;
}

glm::vec3 vec3(const json& value, const std::string& at) {
    if (!value.is_array() || value.size() != 3) {
        const std::string found =
            value.is_array() ? std::to_string(value.size()) + " items" : std::string(value.type_name());
        fail(at, "expected an array of 3 numbers (found " + found + ")");
    }
    glm::vec3 v;
    for (glm::length_t i = 0; i < 3; ++i)
        v[i] = float_number(value[static_cast<std::size_t>(i)], index_path(at, static_cast<std::size_t>(i)));
    return v;
}

// ---------------------------------------------------------------------------------------------------
// Sections

/// The transform keys of `value` (translate, rotate_deg, scale); absent ones keep their defaults.
Transform transform_keys(const json& value, const std::string& at) {
    Transform transform;
    if (const json* v = member(value, "translate")) transform.translate = vec3(*v, key_path(at, "translate"));
    if (const json* v = member(value, "rotate_deg"))
        transform.rotate_deg = vec3(*v, key_path(at, "rotate_deg"));
    if (const json* v = member(value, "scale")) transform.scale = positive_float(*v, key_path(at, "scale"));
    return transform;
}

DomainDesc read_domain(const json& value, const std::string& at) {
    object(value, at);
    allow_keys(
        value, at,
        {"center", "cells", "cell_size", "voxels_per_cell", "branching", "hysteresis", "cascades", "ratio"});
    DomainDesc domain;
    if (const json* v = member(value, "center")) domain.center = vec3(*v, key_path(at, "center"));
    if (const json* v = member(value, "cells")) {
        const std::string cells_at = key_path(at, "cells");
        if (!v->is_array() || v->size() != 3) {
            fail(cells_at, std::string("expected an array of 3 integers (found ") +
                               (v->is_array() ? std::to_string(v->size()) + " items" : v->type_name()) + ")");
        }
        for (glm::length_t i = 0; i < 3; ++i) {
            const auto index = static_cast<std::size_t>(i);
            domain.cells[i] = integer((*v)[index], index_path(cells_at, index), 8, 256);
        }
    }
    if (const json* v = member(value, "cell_size"))
        domain.cell_size = positive_float(*v, key_path(at, "cell_size"));
    if (const json* v = member(value, "voxels_per_cell")) {
        domain.voxels_per_cell = integer(*v, key_path(at, "voxels_per_cell"), 1, 8);
    }
    if (const json* v = member(value, "branching")) {
        const std::string branching_at = key_path(at, "branching");
        const double branching = number(*v, branching_at);
        if (branching != 2.0 && branching != 4.0 && branching != 8.0) {
            fail(branching_at, "must be 2, 4 or 8 (found " + format(branching) + ")");
        }
        domain.branching = static_cast<std::uint32_t>(branching);
    }
    if (const json* v = member(value, "hysteresis")) {
        domain.hysteresis =
            integer(*v, key_path(at, "hysteresis"), 0, std::numeric_limits<std::uint32_t>::max());
    }
    if (const json* v = member(value, "cascades"))
        domain.cascades = integer(*v, key_path(at, "cascades"), 1, 8);
    if (const json* v = member(value, "ratio")) {
        const std::string ratio_at = key_path(at, "ratio");
        const double ratio = number(*v, ratio_at);
        if (ratio != 2.0 && ratio != 4.0) fail(ratio_at, "must be 2 or 4 (found " + format(ratio) + ")");
        domain.ratio = static_cast<std::uint32_t>(ratio);
    }
    const float voxel = domain.cell_size / float(domain.voxels_per_cell);
    if (voxel < kMinVoxelSize) {
        fail(key_path(at, "cell_size"), "voxels of cell_size / voxels_per_cell = " + format(voxel) +
                                            " m are below the smallest, " + format(kMinVoxelSize) + " m");
    }
    if (domain.cell_size > kMaxCellSize) {
        fail(key_path(at, "cell_size"),
             "must be at most " + format(kMaxCellSize) + " m (found " + format(domain.cell_size) + ")");
    }
    if (glm::any(glm::greaterThan(glm::abs(domain.center) / domain.cell_size, glm::vec3(kMaxFocusCells)))) {
        fail(key_path(at, "center"), "is more than 2^19 cells of " + format(domain.cell_size) +
                                         " m from the world's origin, where floats cannot place voxels");
    }
    if (Result<GridDesc> grid = domain_grid(domain); !grid) fail(at, grid.message());
    return domain;
}

fs::path resolve_mesh(const std::string& name, const fs::path& folder, const std::string& at) {
    fs::path path(name);
    if (path.is_relative()) path = folder / path;
    path = path.lexically_normal();
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) {
        if (ec && ec != std::errc::no_such_file_or_directory) {
            fail(at, "cannot access " + path.string() + " (" + ec.message() + ")");
        }
        fail(at, "file not found: " + path.string());
    }
    if (fs::is_directory(status)) fail(at, "is a directory, not a mesh file: " + path.string());
    if (!fs::is_regular_file(status)) fail(at, "not a regular file: " + path.string());
    return path;
}

AnimationDesc read_animation(const json& value, const std::string& at, const fs::path& mesh) {
    object(value, at);
    allow_keys(value, at, {"clip", "speed", "loop", "offset"});
    const std::string extension = lower(mesh.extension().string());
    if (extension != ".gltf" && extension != ".glb") {
        fail(at, "skinned clips need a glTF mesh (.gltf or .glb), not " + mesh.filename().string());
    }
    AnimationDesc animation;
    animation.clip = text(required(value, "clip", at), key_path(at, "clip"));
    if (const json* v = member(value, "speed")) animation.speed = number(*v, key_path(at, "speed"));
    if (const json* v = member(value, "loop")) animation.loop = boolean(*v, key_path(at, "loop"));
    if (const json* v = member(value, "offset")) animation.offset = number(*v, key_path(at, "offset"));
    return animation;
}

std::vector<Keyframe> read_keyframes(const json& value, const std::string& at) {
    array(value, at);
    if (value.empty()) fail(at, "needs at least one keyframe");
    std::vector<Keyframe> keyframes;
    for (std::size_t i = 0; i < value.size(); ++i) {
        const std::string key_at = index_path(at, i);
        const json& item = object(value[i], key_at);
        allow_keys(item, key_at, {"t", "translate", "rotate_deg", "scale", "teleport"});
        Keyframe keyframe;
        const std::string t_at = key_path(key_at, "t");
        keyframe.t = number(required(item, "t", key_at), t_at);
        if (!keyframes.empty() && !(keyframe.t > keyframes.back().t)) {
            fail(t_at, "keyframes must be in increasing time order (" + format(keyframe.t) + " after " +
                           format(keyframes.back().t) + ")");
        }
        keyframe.transform = transform_keys(item, key_at);
        if (const json* v = member(item, "teleport"))
            keyframe.teleport = boolean(*v, key_path(key_at, "teleport"));
        keyframes.push_back(keyframe);
    }
    return keyframes;
}

/// A number within ±kMaxTerrainLength metres.
float terrain_length(const json& value, const std::string& at) {
    const double v = number(value, at);
    if (std::abs(v) > kMaxTerrainLength) {
        fail(at, "must be within ±" + format(kMaxTerrainLength) + " m (found " + format(v) + ")");
    }
    return static_cast<float>(v);
}

/// A number in (0, kMaxTerrainLength] metres.
float terrain_positive_length(const json& value, const std::string& at) {
    const float v = positive_float(value, at);
    if (double(v) > kMaxTerrainLength) {
        fail(at, "must be at most " + format(kMaxTerrainLength) + " m (found " + format(v) + ")");
    }
    return v;
}

/// Exactly two items of `value` (a JSON array), read by `read`.
template <class Read> auto pair_of(const json& value, const std::string& at, const char* what, Read read) {
    if (!value.is_array() || value.size() != 2) {
        const std::string found =
            value.is_array() ? std::to_string(value.size()) + " items" : std::string(value.type_name());
        fail(at, std::string("expected an array of 2 ") + what + " (found " + found + ")");
    }
    return std::array{read(value[0], index_path(at, 0)), read(value[1], index_path(at, 1))};
}

glm::vec2 terrain_point(const json& value, const std::string& at) {
    const auto p = pair_of(value, at, "numbers [x, z]", terrain_length);
    return {p[0], p[1]};
}

TerrainFeature read_terrain_feature(const json& value, const std::string& at) {
    object(value, at);
    const std::string type_at = key_path(at, "type");
    const std::string type = text(required(value, "type", at), type_at);
    TerrainFeature feature;
    if (type == "hill") {
        allow_keys(value, at, {"type", "center", "height", "radius"});
        feature.from = terrain_point(required(value, "center", at), key_path(at, "center"));
        feature.to = feature.from;
        feature.height = terrain_length(required(value, "height", at), key_path(at, "height"));
        feature.width = terrain_positive_length(required(value, "radius", at), key_path(at, "radius"));
    } else if (type == "ridge" || type == "valley") {
        const bool ridge = type == "ridge";
        const char* amount = ridge ? "height" : "depth";
        allow_keys(value, at, {"type", "from", "to", amount, "width"});
        feature.from = terrain_point(required(value, "from", at), key_path(at, "from"));
        feature.to = terrain_point(required(value, "to", at), key_path(at, "to"));
        const std::string amount_at = key_path(at, amount);
        const float height = terrain_length(required(value, amount, at), amount_at);
        if (!ridge && height < 0.0f) {
            fail(amount_at,
                 "must not be negative (found " + format(height) + "); a valley digs by its depth");
        }
        feature.height = ridge ? height : -height;
        feature.width = terrain_positive_length(required(value, "width", at), key_path(at, "width"));
    } else {
        fail(type_at, "unknown terrain feature '" + type + "' (expected hill, ridge or valley)");
    }
    return feature;
}

TerrainNoise read_terrain_noise(const json& value, const std::string& at) {
    object(value, at);
    allow_keys(value, at, {"amplitude", "wavelength", "octaves", "seed"});
    TerrainNoise noise;
    if (const json* v = member(value, "amplitude")) {
        const std::string amplitude_at = key_path(at, "amplitude");
        noise.amplitude = terrain_length(*v, amplitude_at);
        if (noise.amplitude < 0.0f)
            fail(amplitude_at, "must not be negative (found " + format(noise.amplitude) + ")");
    }
    if (const json* v = member(value, "wavelength")) {
        const std::string wavelength_at = key_path(at, "wavelength");
        noise.wavelength = terrain_positive_length(*v, wavelength_at);
        // Keeps lattice coordinates (up to 100 km / wavelength · 2^15) well inside 64-bit integers.
        if (noise.wavelength < 0.01f)
            fail(wavelength_at, "must be at least 0.01 m (found " + format(noise.wavelength) + ")");
    }
    if (const json* v = member(value, "octaves")) noise.octaves = integer(*v, key_path(at, "octaves"), 1, 16);
    if (const json* v = member(value, "seed")) {
        noise.seed = integer(*v, key_path(at, "seed"), 0, std::numeric_limits<std::uint32_t>::max());
    }
    return noise;
}

TerrainDesc read_terrain(const json& value, const std::string& at) {
    object(value, at);
    allow_keys(value, at, {"size", "samples", "base", "features", "noise"});
    TerrainDesc terrain;
    if (const json* v = member(value, "size")) {
        const auto size = pair_of(*v, key_path(at, "size"), "numbers [sx, sz]", terrain_positive_length);
        terrain.size = {size[0], size[1]};
    }
    if (const json* v = member(value, "samples")) {
        const std::string samples_at = key_path(at, "samples");
        const auto samples =
            pair_of(*v, samples_at, "integers [nx, nz]", [](const json& item, const std::string& item_at) {
                return integer(item, item_at, 1, kMaxTerrainSamples);
            });
        terrain.samples = {samples[0], samples[1]};
        const std::uint64_t triangles = 2ull * samples[0] * samples[1];
        if (triangles > kMaxTerrainTriangles) {
            fail(samples_at, "2 · nx · nz = " + std::to_string(triangles) + " triangles, more than " +
                                 std::to_string(kMaxTerrainTriangles));
        }
    }
    if (const json* v = member(value, "base")) terrain.base = terrain_length(*v, key_path(at, "base"));
    if (const json* v = member(value, "features")) {
        const std::string features_at = key_path(at, "features");
        array(*v, features_at);
        if (v->size() > kMaxTerrainFeatures) {
            fail(features_at, "at most " + std::to_string(kMaxTerrainFeatures) + " features (found " +
                                  std::to_string(v->size()) + ")");
        }
        for (std::size_t i = 0; i < v->size(); ++i)
            terrain.features.push_back(read_terrain_feature((*v)[i], index_path(features_at, i)));
    }
    if (const json* v = member(value, "noise")) terrain.noise = read_terrain_noise(*v, key_path(at, "noise"));
    return terrain;
}

SceneObject read_object(const json& value, const std::string& at, const fs::path& folder) {
    object(value, at);
    allow_keys(value, at, {"mesh", "static", "transform", "keyframes", "animation", "terrain"});
    SceneObject object_desc;
    const std::string mesh_at = key_path(at, "mesh");
    const json* mesh = member(value, "mesh");
    const json* terrain = member(value, "terrain");
    if (mesh != nullptr && terrain != nullptr)
        fail(key_path(at, "terrain"), "an object has either a mesh or a terrain, not both");
    if (mesh == nullptr && terrain == nullptr)
        fail(mesh_at, "missing required key (an object needs a mesh or a terrain)");
    if (mesh != nullptr) object_desc.mesh = resolve_mesh(text(*mesh, mesh_at), folder, mesh_at);
    if (terrain != nullptr) object_desc.terrain = read_terrain(*terrain, key_path(at, "terrain"));
    if (const json* v = member(value, "static")) object_desc.is_static = boolean(*v, key_path(at, "static"));
    const json* transform = member(value, "transform");
    const json* keyframes = member(value, "keyframes");
    const json* animation = member(value, "animation");
    if (transform != nullptr) {
        const std::string transform_at = key_path(at, "transform");
        object(*transform, transform_at);
        allow_keys(*transform, transform_at, {"translate", "rotate_deg", "scale"});
        object_desc.transform = transform_keys(*transform, transform_at);
    }
    if (keyframes != nullptr) {
        const std::string keyframes_at = key_path(at, "keyframes");
        if (transform != nullptr)
            fail(keyframes_at, "an object has either a transform or keyframes, not both");
        if (object_desc.is_static) fail(keyframes_at, "a static object cannot have keyframes");
        object_desc.keyframes = read_keyframes(*keyframes, keyframes_at);
    }
    if (animation != nullptr) {
        const std::string animation_at = key_path(at, "animation");
        if (object_desc.is_static) fail(animation_at, "a static object cannot be animated");
        if (object_desc.terrain) fail(animation_at, "a terrain cannot be animated (only glTF meshes can)");
        object_desc.animation = read_animation(*animation, animation_at, object_desc.mesh);
    }
    return object_desc;
}

EmitterDesc read_emitter(const json& value, const std::string& at) {
    object(value, at);
    allow_keys(value, at,
               {"type", "position", "direction", "radius", "strength", "falloff", "shape", "length", "path"});
    EmitterDesc emitter;
    const std::string type_at = key_path(at, "type");
    emitter.type = text(required(value, "type", at), type_at);
    constexpr std::string_view kTypes[] = {"directional", "omni", "vortex", "motor"};
    if (std::find(std::begin(kTypes), std::end(kTypes), emitter.type) == std::end(kTypes)) {
        fail(type_at,
             "unknown emitter type '" + emitter.type + "' (expected directional, omni, vortex or motor)");
    }
    if (const json* v = member(value, "position")) emitter.position = vec3(*v, key_path(at, "position"));
    if (const json* v = member(value, "direction")) {
        const std::string direction_at = key_path(at, "direction");
        const glm::dvec3 direction(vec3(*v, direction_at));
        const double length = glm::length(direction);
        if (!(length > 0.0)) fail(direction_at, "must not be the zero vector");
        emitter.direction = glm::vec3(direction / length);
    }
    if (const json* v = member(value, "radius")) emitter.radius = positive_float(*v, key_path(at, "radius"));
    if (const json* v = member(value, "strength")) {
        const std::string strength_at = key_path(at, "strength");
        emitter.strength = float_number(*v, strength_at);
        if (std::abs(emitter.strength) > kMaxEmitterStrength) {
            fail(strength_at, "must be within ±" + format(kMaxEmitterStrength) + " m/s (found " +
                                  format(emitter.strength) + ")");
        }
    }
    if (const json* v = member(value, "falloff")) {
        const std::string falloff_at = key_path(at, "falloff");
        emitter.falloff = float_number(*v, falloff_at);
        if (emitter.falloff < 0.0f || emitter.falloff > kMaxEmitterFalloff)
            fail(falloff_at, "must be in [0, " + format(kMaxEmitterFalloff) + "] (found " +
                                 format(emitter.falloff) + ")");
    }
    const bool motor = emitter.type == "motor";
    if (const json* v = member(value, "shape")) {
        const std::string shape_at = key_path(at, "shape");
        if (!motor) fail(shape_at, "only motors have a shape");
        emitter.shape = text(*v, shape_at);
        if (emitter.shape != "capsule" && emitter.shape != "cone")
            fail(shape_at, "unknown motor shape '" + emitter.shape + "' (expected capsule or cone)");
    }
    if (const json* v = member(value, "length")) {
        const std::string length_at = key_path(at, "length");
        if (!motor) fail(length_at, "only motors have a length");
        emitter.length = float_number(*v, length_at);
        if (emitter.length < 0.0f)
            fail(length_at, "must not be negative (found " + format(emitter.length) + ")");
    }
    if (motor && emitter.shape == "cone" && !(emitter.length > 0.0f))
        fail(key_path(at, "length"), "a cone motor needs a length greater than 0");
    if (const json* v = member(value, "path")) {
        const std::string path_at = key_path(at, "path");
        array(*v, path_at);
        if (v->empty()) fail(path_at, "needs at least one key");
        for (std::size_t i = 0; i < v->size(); ++i) {
            const std::string key_at = index_path(path_at, i);
            const json& item = object((*v)[i], key_at);
            allow_keys(item, key_at, {"t", "position"});
            EmitterKey key;
            const std::string t_at = key_path(key_at, "t");
            key.t = number(required(item, "t", key_at), t_at);
            if (!emitter.path.empty() && !(key.t > emitter.path.back().t))
                fail(t_at, "path keys must be in increasing time order (" + format(key.t) + " after " +
                               format(emitter.path.back().t) + ")");
            key.position = vec3(required(item, "position", key_at), key_path(key_at, "position"));
            emitter.path.push_back(key);
        }
    }
    return emitter;
}

SolverSettings read_solver(const json& value, const std::string& at) {
    object(value, at);
    allow_keys(value, at,
               {"advection", "pressure", "tolerance", "max_cycles", "max_iterations", "vorticity",
                "viscosity", "max_solid_speed", "cycles_per_step"});
    SolverSettings solver;
    if (const json* v = member(value, "advection")) {
        const std::string advection_at = key_path(at, "advection");
        solver.advection = text(*v, advection_at);
        if (solver.advection != "maccormack" && solver.advection != "semi_lagrangian" &&
            solver.advection != "none")
            fail(advection_at, "unknown advection '" + solver.advection +
                                   "' (expected maccormack, semi_lagrangian or none)");
    }
    if (const json* v = member(value, "pressure")) {
        const std::string pressure_at = key_path(at, "pressure");
        solver.pressure = text(*v, pressure_at);
        if (solver.pressure != "mgpcg" && solver.pressure != "multigrid" && solver.pressure != "jacobi")
            fail(pressure_at,
                 "unknown pressure solver '" + solver.pressure + "' (expected mgpcg, multigrid or jacobi)");
    }
    if (const json* v = member(value, "tolerance")) {
        const std::string tolerance_at = key_path(at, "tolerance");
        solver.tolerance = positive_float(*v, tolerance_at);
        if (!(solver.tolerance < 1.0f))
            fail(tolerance_at, "must be less than 1 (found " + format(solver.tolerance) + ")");
    }
    if (const json* v = member(value, "max_cycles"))
        solver.max_cycles = integer(*v, key_path(at, "max_cycles"), 1, 1000);
    if (const json* v = member(value, "cycles_per_step"))
        solver.cycles_per_step = integer(*v, key_path(at, "cycles_per_step"), 0, 1000);
    if (const json* v = member(value, "max_iterations"))
        solver.max_iterations = integer(*v, key_path(at, "max_iterations"), 1, 1000000);
    if (const json* v = member(value, "vorticity")) {
        const std::string vorticity_at = key_path(at, "vorticity");
        solver.vorticity = float_number(*v, vorticity_at);
        if (solver.vorticity < 0.0f || solver.vorticity > 10.0f)
            fail(vorticity_at, "must be from 0 to 10 (found " + format(solver.vorticity) + ")");
    }
    if (const json* v = member(value, "viscosity")) {
        const std::string viscosity_at = key_path(at, "viscosity");
        solver.viscosity = float_number(*v, viscosity_at);
        if (solver.viscosity < 0.0f)
            fail(viscosity_at, "must not be negative (found " + format(solver.viscosity) + ")");
    }
    if (const json* v = member(value, "max_solid_speed")) {
        const std::string speed_at = key_path(at, "max_solid_speed");
        solver.max_solid_speed = positive_float(*v, speed_at);
        if (solver.max_solid_speed > 256.0f)
            fail(speed_at, "must be at most 256 m/s (found " + format(solver.max_solid_speed) + ")");
    }
    return solver;
}

SceneDesc read_scene(const json& root, const fs::path& file) {
    if (!root.is_object()) {
        throw Invalid{std::string("the top level must be a JSON object (found ") + root.type_name() + ")"};
    }
    allow_keys(root, "", {"dt", "domain", "ambient", "objects", "emitters", "solver"});
    SceneDesc scene;
    scene.file = file;
    std::error_code ec;
    const fs::path folder = fs::absolute(file, ec).parent_path();
    if (ec) throw Invalid{"cannot resolve the scene file's folder (" + ec.message() + ")"};

    if (const json* v = member(root, "dt")) {
        scene.dt = number(*v, "dt");
        if (!(scene.dt > 0.0 && scene.dt <= kMaxStep))
            fail("dt", "must be in (0, " + format(kMaxStep) + "] seconds (found " + format(scene.dt) + ")");
        require_normal_float(scene.dt, "dt");
    }
    if (const json* v = member(root, "domain")) scene.domain = read_domain(*v, "domain");
    if (const json* v = member(root, "ambient")) {
        object(*v, "ambient");
        allow_keys(*v, "ambient", {"velocity"});
        if (const json* velocity = member(*v, "velocity")) {
            scene.ambient_velocity = vec3(*velocity, "ambient.velocity");
            if (glm::length(scene.ambient_velocity) > kMaxAmbientSpeed)
                fail("ambient.velocity", "must be below " + format(kMaxAmbientSpeed) + " m/s (found " +
                                             format(glm::length(scene.ambient_velocity)) + ")");
        }
    }
    if (const json* v = member(root, "objects")) {
        array(*v, "objects");
        for (std::size_t i = 0; i < v->size(); ++i)
            scene.objects.push_back(read_object((*v)[i], index_path("objects", i), folder));
    }
    if (const json* v = member(root, "emitters")) {
        array(*v, "emitters");
        if (v->size() > kMaxEmitterCount) {
            fail("emitters", "at most " + std::to_string(kMaxEmitterCount) + " emitters (found " +
                                 std::to_string(v->size()) + ")");
        }
        for (std::size_t i = 0; i < v->size(); ++i)
            scene.emitters.push_back(read_emitter((*v)[i], index_path("emitters", i)));
    }
    if (const json* v = member(root, "solver")) scene.solver = read_solver(*v, "solver");
    return scene;
}

glm::dmat4 rotation_xyz(const glm::dvec3& degrees) {
    const glm::dmat4 identity(1.0);
    return glm::rotate(identity, glm::radians(degrees.z), glm::dvec3(0, 0, 1)) *
           glm::rotate(identity, glm::radians(degrees.y), glm::dvec3(0, 1, 0)) *
           glm::rotate(identity, glm::radians(degrees.x), glm::dvec3(1, 0, 0));
}

} // namespace

glm::mat4 Transform::matrix() const {
    // Composed in double so that quarter turns leave no visible residue (cos 90° is ~6e-17, not 4e-8).
    const glm::dmat4 m = glm::translate(glm::dmat4(1.0), glm::dvec3(translate)) *
                         rotation_xyz(glm::dvec3(rotate_deg)) *
                         glm::scale(glm::dmat4(1.0), glm::dvec3(scale));
    return glm::mat4(m);
}

Result<SceneDesc> load_scene(const std::filesystem::path& file) {
    std::string reason;
    try {
        return read_scene(parse_document(file), file);
    } catch (const Invalid& invalid) {
        reason = invalid.message;
    } catch (const std::bad_alloc&) {
        reason = "out of memory";
    } catch (const std::exception& e) {
        reason = "unexpected error: " + detail::clean_message(e.what());
    }
    return Result<SceneDesc>::failure(file.string() + ": " + reason);
}

glm::mat4 object_matrix(const SceneObject& object, double t) {
    const std::vector<Keyframe>& keys = object.keyframes;
    if (keys.empty()) return object.transform.matrix();
    if (!(t > keys.front().t)) return keys.front().transform.matrix();
    if (t >= keys.back().t) return keys.back().transform.matrix();
    const auto next = std::upper_bound(keys.begin(), keys.end(), t,
                                       [](double time, const Keyframe& key) { return time < key.t; });
    const Transform& a = std::prev(next)->transform;
    const Transform& b = next->transform;
    if (next->teleport) return a.matrix();
    const double s = (t - std::prev(next)->t) / (next->t - std::prev(next)->t);
    Transform between;
    between.translate = glm::vec3(glm::mix(glm::dvec3(a.translate), glm::dvec3(b.translate), s));
    between.rotate_deg = glm::vec3(glm::mix(glm::dvec3(a.rotate_deg), glm::dvec3(b.rotate_deg), s));
    between.scale = static_cast<float>(glm::mix(double{a.scale}, double{b.scale}, s));
    return between.matrix();
}

bool object_jumps(const SceneObject& object, double t0, double t1) {
    const std::vector<Keyframe>& keys = object.keyframes;
    for (std::size_t i = 1; i < keys.size(); ++i) {
        const bool ends_now = keys[i].t > t0 && keys[i].t <= t1;
        if (ends_now && (keys[i].teleport || keys[i].t - keys[i - 1].t < t1 - t0)) return true;
    }
    return false;
}

glm::vec3 emitter_position(const EmitterDesc& emitter, double t) {
    const std::vector<EmitterKey>& path = emitter.path;
    if (path.empty()) return emitter.position;
    if (t <= path.front().t) return path.front().position;
    if (t >= path.back().t) return path.back().position;
    const auto next = std::upper_bound(path.begin(), path.end(), t,
                                       [](double time, const EmitterKey& key) { return time < key.t; });
    const EmitterKey& a = *(next - 1);
    const EmitterKey& b = *next;
    const double s = (t - a.t) / (b.t - a.t);
    return glm::vec3(glm::mix(glm::dvec3(a.position), glm::dvec3(b.position), s));
}

} // namespace gust
