// Checks a glTF file before tinygltf parses it: the GLB framing, and the JSON against the property
// types of the glTF 2.0 core schema and its required extensions (import_gltf.cpp says why).
#include "gltf_detail.hpp"
#include "import_detail.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace gust::detail {
namespace {

using nlohmann::json;

// ---------------------------------------------------------------------------------------------------
// Property types of the glTF 2.0 core schema

enum class Type { any, string, number, index, boolean, object, array };

struct ObjectSchema;

struct Field {
    std::string_view name;
    Type type;
    const ObjectSchema* object = nullptr; ///< schema of the object, or of each object in the array
    Type item = Type::any;                ///< type of each array item
    std::size_t length = 0;               ///< required array length; 0 for any
    bool required = false;                ///< the schema requires it (tinygltf drops or fails without a word)
};

struct ObjectSchema {
    std::span<const Field> fields;
    Type values = Type::any; ///< for maps (attributes): the type of every member
};

constexpr Field kTextureInfoFields[] = {{"index", Type::index}, {"texCoord", Type::index}};
constexpr ObjectSchema kTextureInfo{kTextureInfoFields};
constexpr Field kNormalTextureFields[] = {
    {"index", Type::index}, {"texCoord", Type::index}, {"scale", Type::number}};
constexpr ObjectSchema kNormalTexture{kNormalTextureFields};
constexpr Field kOcclusionTextureFields[] = {
    {"index", Type::index}, {"texCoord", Type::index}, {"strength", Type::number}};
constexpr ObjectSchema kOcclusionTexture{kOcclusionTextureFields};
constexpr Field kPbrFields[] = {
    {"baseColorFactor", Type::array, nullptr, Type::number, 4},
    {"baseColorTexture", Type::object, &kTextureInfo},
    {"metallicFactor", Type::number},
    {"roughnessFactor", Type::number},
    {"metallicRoughnessTexture", Type::object, &kTextureInfo},
};
constexpr ObjectSchema kPbr{kPbrFields};
constexpr Field kMaterialFields[] = {
    {"pbrMetallicRoughness", Type::object, &kPbr},
    {"normalTexture", Type::object, &kNormalTexture},
    {"occlusionTexture", Type::object, &kOcclusionTexture},
    {"emissiveTexture", Type::object, &kTextureInfo},
    {"emissiveFactor", Type::array, nullptr, Type::number, 3},
    {"alphaMode", Type::string},
    {"alphaCutoff", Type::number},
    {"doubleSided", Type::boolean},
};
constexpr ObjectSchema kMaterial{kMaterialFields};
constexpr Field kAssetFields[] = {{"copyright", Type::string},
                                  {"generator", Type::string},
                                  {"version", Type::string},
                                  {"minVersion", Type::string}};
constexpr ObjectSchema kAsset{kAssetFields};
constexpr Field kSceneFields[] = {{"nodes", Type::array, nullptr, Type::index}};
constexpr ObjectSchema kScene{kSceneFields};
constexpr Field kNodeFields[] = {
    {"camera", Type::index},
    {"children", Type::array, nullptr, Type::index},
    {"skin", Type::index},
    {"matrix", Type::array, nullptr, Type::number, 16},
    {"mesh", Type::index},
    {"rotation", Type::array, nullptr, Type::number, 4},
    {"scale", Type::array, nullptr, Type::number, 3},
    {"translation", Type::array, nullptr, Type::number, 3},
    {"weights", Type::array, nullptr, Type::number},
};
constexpr ObjectSchema kNode{kNodeFields};
constexpr ObjectSchema kAttributes{{}, Type::index};
constexpr Field kPrimitiveFields[] = {
    {"attributes", Type::object, &kAttributes},
    {"indices", Type::index},
    {"material", Type::index},
    {"mode", Type::index},
    {"targets", Type::array, &kAttributes, Type::object},
};
constexpr ObjectSchema kPrimitive{kPrimitiveFields};
constexpr Field kMeshFields[] = {
    {"primitives", Type::array, &kPrimitive, Type::object},
    {"weights", Type::array, nullptr, Type::number},
};
constexpr ObjectSchema kMesh{kMeshFields};
constexpr Field kSparseIndicesFields[] = {
    {"bufferView", Type::index}, {"byteOffset", Type::index}, {"componentType", Type::index}};
constexpr ObjectSchema kSparseIndices{kSparseIndicesFields};
constexpr Field kSparseValuesFields[] = {{"bufferView", Type::index}, {"byteOffset", Type::index}};
constexpr ObjectSchema kSparseValues{kSparseValuesFields};
constexpr Field kSparseFields[] = {
    {"count", Type::index},
    {"indices", Type::object, &kSparseIndices},
    {"values", Type::object, &kSparseValues},
};
constexpr ObjectSchema kSparse{kSparseFields};
constexpr Field kAccessorFields[] = {
    {"bufferView", Type::index},
    {"byteOffset", Type::index},
    {"componentType", Type::index},
    {"normalized", Type::boolean},
    {"count", Type::index},
    {"type", Type::string},
    {"max", Type::array, nullptr, Type::number},
    {"min", Type::array, nullptr, Type::number},
    {"sparse", Type::object, &kSparse},
};
constexpr ObjectSchema kAccessor{kAccessorFields};
constexpr Field kBufferViewFields[] = {
    {"buffer", Type::index},     {"byteOffset", Type::index}, {"byteLength", Type::index},
    {"byteStride", Type::index}, {"target", Type::index},
};
constexpr ObjectSchema kBufferView{kBufferViewFields};
constexpr Field kBufferFields[] = {{"uri", Type::string}, {"byteLength", Type::index}};
constexpr ObjectSchema kBuffer{kBufferFields};
constexpr Field kTextureFields[] = {{"sampler", Type::index}, {"source", Type::index}};
constexpr ObjectSchema kTexture{kTextureFields};
constexpr Field kImageFields[] = {
    {"uri", Type::string}, {"mimeType", Type::string}, {"bufferView", Type::index}};
constexpr ObjectSchema kImage{kImageFields};
constexpr Field kSamplerFields[] = {
    {"magFilter", Type::index}, {"minFilter", Type::index}, {"wrapS", Type::index}, {"wrapT", Type::index}};
constexpr ObjectSchema kSampler{kSamplerFields};
constexpr Field kSkinFields[] = {
    {"inverseBindMatrices", Type::index},
    {"skeleton", Type::index},
    {"joints", Type::array, nullptr, Type::index, 0, true},
};
constexpr ObjectSchema kSkin{kSkinFields};
constexpr Field kChannelTargetFields[] = {{"node", Type::index},
                                          {"path", Type::string, nullptr, Type::any, 0, true}};
constexpr ObjectSchema kChannelTarget{kChannelTargetFields};
constexpr Field kChannelFields[] = {{"sampler", Type::index, nullptr, Type::any, 0, true},
                                    {"target", Type::object, &kChannelTarget, Type::any, 0, true}};
constexpr ObjectSchema kChannel{kChannelFields};
constexpr Field kAnimationSamplerFields[] = {{"input", Type::index, nullptr, Type::any, 0, true},
                                             {"interpolation", Type::string},
                                             {"output", Type::index, nullptr, Type::any, 0, true}};
constexpr ObjectSchema kAnimationSampler{kAnimationSamplerFields};
constexpr Field kAnimationFields[] = {
    {"channels", Type::array, &kChannel, Type::object, 0, true},
    {"samplers", Type::array, &kAnimationSampler, Type::object, 0, true},
};
constexpr ObjectSchema kAnimation{kAnimationFields};
constexpr Field kOrthographicFields[] = {
    {"xmag", Type::number}, {"ymag", Type::number}, {"zfar", Type::number}, {"znear", Type::number}};
constexpr ObjectSchema kOrthographic{kOrthographicFields};
constexpr Field kPerspectiveFields[] = {
    {"aspectRatio", Type::number}, {"yfov", Type::number}, {"zfar", Type::number}, {"znear", Type::number}};
constexpr ObjectSchema kPerspective{kPerspectiveFields};
constexpr Field kCameraFields[] = {
    {"orthographic", Type::object, &kOrthographic},
    {"perspective", Type::object, &kPerspective},
    {"type", Type::string},
};
constexpr ObjectSchema kCamera{kCameraFields};
constexpr Field kRootFields[] = {
    {"asset", Type::object, &kAsset},
    {"scene", Type::index},
    {"scenes", Type::array, &kScene, Type::object},
    {"nodes", Type::array, &kNode, Type::object},
    {"meshes", Type::array, &kMesh, Type::object},
    {"accessors", Type::array, &kAccessor, Type::object},
    {"bufferViews", Type::array, &kBufferView, Type::object},
    {"buffers", Type::array, &kBuffer, Type::object},
    {"materials", Type::array, &kMaterial, Type::object},
    {"textures", Type::array, &kTexture, Type::object},
    {"images", Type::array, &kImage, Type::object},
    {"samplers", Type::array, &kSampler, Type::object},
    {"skins", Type::array, &kSkin, Type::object},
    {"animations", Type::array, &kAnimation, Type::object},
    {"cameras", Type::array, &kCamera, Type::object},
    {"extensionsUsed", Type::array, nullptr, Type::string},
    {"extensionsRequired", Type::array, nullptr, Type::string},
};
constexpr ObjectSchema kRoot{kRootFields};

bool matches(const json& value, Type type) {
    switch (type) {
    case Type::any:
        return true;
    case Type::string:
        return value.is_string();
    case Type::number:
        return value.is_number();
    case Type::index:
        if (value.is_number_unsigned()) return true;
        if (value.is_number_integer()) return value.get<std::int64_t>() >= 0;
        if (value.is_number_float()) {
            const double v = value.get<double>();
            return v >= 0 && std::floor(v) == v;
        }
        return false;
    case Type::boolean:
        return value.is_boolean();
    case Type::object:
        return value.is_object();
    case Type::array:
        return value.is_array();
    }
    return false;
}

std::string_view describe(Type type) {
    switch (type) {
    case Type::any:
        return "any value";
    case Type::string:
        return "a string";
    case Type::number:
        return "a number";
    case Type::index:
        return "a non-negative integer";
    case Type::boolean:
        return "a boolean";
    case Type::object:
        return "an object";
    case Type::array:
        return "an array";
    }
    return "?";
}

Status type_error(const std::string& pointer, Type expected, const json& value) {
    return Status::failure("invalid glTF: " + pointer + " must be " + std::string(describe(expected)) +
                           " (found " + value.type_name() + ")");
}

Status check_object(const json& object, const ObjectSchema& schema, const std::string& pointer);

Status check_field(const json& value, const Field& field, const std::string& pointer) {
    if (!matches(value, field.type)) return type_error(pointer, field.type, value);
    if (field.type == Type::object) return check_object(value, *field.object, pointer);
    if (field.type != Type::array) return {};
    if (field.length != 0 && value.size() != field.length) {
        return Status::failure("invalid glTF: " + pointer + " must have " + std::to_string(field.length) +
                               " items (found " + std::to_string(value.size()) + ")");
    }
    for (std::size_t i = 0; i < value.size(); ++i) {
        const std::string at = pointer + "/" + std::to_string(i);
        if (!matches(value[i], field.item)) return type_error(at, field.item, value[i]);
        if (field.object) {
            if (Status status = check_object(value[i], *field.object, at); !status) return status;
        }
    }
    return {};
}

Status check_object(const json& object, const ObjectSchema& schema, const std::string& pointer) {
    // The animation and skin properties the schema requires: without them tinygltf dropped a channel (the
    // clip froze) or failed without a reason (a skin without joints).
    for (const Field& field : schema.fields)
        if (field.required && !object.contains(field.name))
            return Status::failure("invalid glTF: " + pointer + "/" + std::string(field.name) +
                                   " is required");
    for (const auto& [key, value] : object.items()) {
        const std::string at = pointer + "/" + key;
        if (schema.values != Type::any) {
            if (!matches(value, schema.values)) return type_error(at, schema.values, value);
        } else if (key == "name") {
            if (!value.is_string()) return type_error(at, Type::string, value);
        } else if (key == "extensions") {
            if (!value.is_object()) return type_error(at, Type::object, value);
            for (const auto& [extension, body] : value.items()) {
                if (!body.is_object()) return type_error(at + "/" + extension, Type::object, body);
            }
        } else {
            const std::string_view name = key;
            const auto field = std::find_if(schema.fields.begin(), schema.fields.end(),
                                            [name](const Field& f) { return f.name == name; });
            if (field == schema.fields.end()) continue; // extras and unknown properties are free-form
            if (Status status = check_field(value, *field, at); !status) return status;
        }
    }
    return {};
}

// Required extensions that change nothing about geometry; any other required extension (mesh
// compression, quantization, instancing) would change what the positions and indices mean.
bool geometry_neutral(std::string_view extension) {
    constexpr std::string_view kNeutral[] = {"KHR_texture_transform", "KHR_texture_basisu",
                                             "EXT_texture_webp",      "EXT_texture_avif",
                                             "KHR_lights_punctual",   "KHR_xmp_json_ld"};
    return extension.starts_with("KHR_materials_") ||
           std::find(std::begin(kNeutral), std::end(kNeutral), extension) != std::end(kNeutral);
}

// ---------------------------------------------------------------------------------------------------
// Container

std::uint32_t read_u32(const unsigned char* p) {
    return std::uint32_t{p[0]} | std::uint32_t{p[1]} << 8 | std::uint32_t{p[2]} << 16 |
           std::uint32_t{p[3]} << 24;
}

} // namespace

bool is_glb(const std::vector<unsigned char>& bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

Result<std::string_view> json_text(const std::vector<unsigned char>& bytes) {
    using R = Result<std::string_view>;
    const auto* chars = reinterpret_cast<const char*>(bytes.data());
    if (!is_glb(bytes)) return std::string_view(chars, bytes.size());
    constexpr std::size_t kHeader = 20; // 12-byte file header + 8-byte chunk header
    if (bytes.size() < kHeader) return R::failure("file truncated: GLB header needs 20 bytes");
    const std::uint32_t version = read_u32(bytes.data() + 4);
    const std::uint32_t length = read_u32(bytes.data() + 8);
    const std::uint32_t chunk_length = read_u32(bytes.data() + 12);
    const std::uint32_t chunk_type = read_u32(bytes.data() + 16);
    if (version != 2) {
        return R::failure("unsupported GLB version " + std::to_string(version) + " (expected 2)");
    }
    if (length < kHeader)
        return R::failure("GLB header declares a length of " + std::to_string(length) + " bytes");
    if (length > bytes.size()) {
        return R::failure("file truncated: GLB header declares " + std::to_string(length) +
                          " bytes but the file has " + std::to_string(bytes.size()));
    }
    if (chunk_type != 0x4E4F534Au) return R::failure("first GLB chunk is not JSON");
    if (chunk_length > length - kHeader) return R::failure("GLB JSON chunk runs past the end of the file");
    return std::string_view(chars + kHeader, chunk_length);
}

Status check_json(std::string_view text) {
    json root;
    try {
        root = json::parse(text.begin(), text.end());
    } catch (const json::exception& e) {
        return Status::failure("invalid JSON: " + clean_message(e.what()));
    }
    if (!root.is_object()) return Status::failure("invalid glTF: the JSON root is not an object");
    // glTF 1.0 keeps its arrays as objects; say so instead of reporting the first schema mismatch.
    if (const auto asset = root.find("asset"); asset != root.end() && asset->is_object())
        if (const auto version = asset->find("version");
            version != asset->end() && version->is_string() &&
            version->get_ref<const std::string&>().rfind("1.", 0) == 0)
            return Status::failure("glTF " + version->get<std::string>() +
                                   " is not supported (only glTF 2.0; convert the file first)");
    if (Status status = check_object(root, kRoot, ""); !status) return status;
    if (const auto required = root.find("extensionsRequired"); required != root.end()) {
        for (const json& name : *required) {
            const auto& extension = name.get_ref<const std::string&>();
            if (!geometry_neutral(extension)) {
                return Status::failure("required extension " + extension + " is not supported");
            }
        }
    }
    return {};
}

} // namespace gust::detail
