// Reading what animates a glTF scene: the node hierarchy, the skins (joints, inverse bind matrices and
// every vertex's JOINTS_n/WEIGHTS_n influences) and the animation clips' channels, every accessor
// checked. animated_mesh.cpp evaluates them.
#include "gltf_rig.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust {

namespace anim = detail::anim;

namespace {

using anim::Interpolation;
using anim::Path;

constexpr int kUnsigned[] = {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT};
constexpr int kSignedOrUnsigned[] = {TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                     TINYGLTF_COMPONENT_TYPE_SHORT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT};

std::string accessor_name(int index) {
    return "accessor " + std::to_string(index);
}

// One component as glTF reads it: floats as stored, normalised integers mapped to [0, 1] or [-1, 1]
// (glTF 2.0, section 3.11), other integers as their value.
double component(const unsigned char* p, int type, bool normalized) {
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        float v;
        std::memcpy(&v, p, sizeof v);
        return v;
    }
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        std::int8_t v;
        std::memcpy(&v, p, sizeof v);
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? *p / 255.0 : *p;
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        std::int16_t v;
        std::memcpy(&v, p, sizeof v);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    default: { // unsigned short: read_vectors admits no other component type
        std::uint16_t v;
        std::memcpy(&v, p, sizeof v);
        return normalized ? v / 65535.0 : v;
    }
    }
}

/// The component types an accessor may have.
struct Format {
    bool floats;                   ///< float components
    std::span<const int> integers; ///< integer component types
    bool normalized;               ///< whether the integer ones must be normalised (else must not be)
    const char* text;              ///< for messages
};

constexpr Format kFloat{true, {}, false, "float"};
constexpr Format kJoints{false, kUnsigned, false, "unsigned byte or short"};
constexpr Format kWeights{true, kUnsigned, true, "float or normalized unsigned byte or short"};
constexpr Format kRotations{true, kSignedOrUnsigned, true, "float or normalized integer"};

/// Every element of accessor `index` as up to four doubles (missing components 0); the accessor must
/// be of `type` with components in `format`.
Result<std::vector<glm::dvec4>> read_vectors(const tinygltf::Model& model, int index, std::size_t file_size,
                                             int type, const Format& format, const std::string& what) {
    using R = Result<std::vector<glm::dvec4>>;
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
        return R::failure(what + " refers to missing " + accessor_name(index));
    }
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    const int components = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(type));
    const int kind = accessor.componentType;
    const bool allowed =
        kind == TINYGLTF_COMPONENT_TYPE_FLOAT
            ? format.floats
            : std::find(format.integers.begin(), format.integers.end(), kind) != format.integers.end() &&
                  accessor.normalized == format.normalized;
    if (accessor.type != type || !allowed) {
        const char* type_name = type == TINYGLTF_TYPE_SCALAR ? "SCALAR"
                                : type == TINYGLTF_TYPE_VEC3 ? "VEC3"
                                                             : "VEC4";
        return R::failure(what + " " + accessor_name(index) + " must be " + format.text + " " + type_name);
    }
    const auto size =
        static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(static_cast<std::uint32_t>(kind)));
    const bool normalized = accessor.normalized;
    return detail::read_accessor<glm::dvec4>(model, index, file_size, [&](const unsigned char* p) {
        glm::dvec4 v(0.0);
        for (int c = 0; c < components; ++c)
            v[c] = component(p + static_cast<std::size_t>(c) * size, kind, normalized);
        return v;
    });
}

Result<std::vector<glm::dmat4>> read_matrices(const tinygltf::Model& model, int index, std::size_t file_size,
                                              const std::string& what) {
    using R = Result<std::vector<glm::dmat4>>;
    if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size()) {
        return R::failure(what + " refers to missing " + accessor_name(index));
    }
    const tinygltf::Accessor& accessor = model.accessors[static_cast<std::size_t>(index)];
    if (accessor.type != TINYGLTF_TYPE_MAT4 || accessor.componentType != TINYGLTF_COMPONENT_TYPE_FLOAT) {
        return R::failure(what + " " + accessor_name(index) + " must be float MAT4");
    }
    return detail::read_accessor<glm::dmat4>(model, index, file_size, [](const unsigned char* p) {
        float m[16];
        std::memcpy(m, p, sizeof m);
        return glm::dmat4(glm::make_mat4(m));
    });
}

bool finite(const glm::dvec4& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

bool finite(const glm::dmat4& m) {
    return finite(m[0]) && finite(m[1]) && finite(m[2]) && finite(m[3]);
}

std::string clip_name(const tinygltf::Model& model, std::size_t clip) {
    const std::string& name = model.animations[clip].name;
    return name.empty() ? "clip" + std::to_string(clip) : name;
}

std::vector<anim::Node> read_nodes(const tinygltf::Model& model) {
    std::vector<anim::Node> nodes(model.nodes.size());
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        const tinygltf::Node& source = model.nodes[i];
        anim::Node& node = nodes[i];
        node.rest = detail::local_transform(source);
        node.has_matrix = source.matrix.size() == 16;
        if (source.translation.size() == 3) node.translation = glm::make_vec3(source.translation.data());
        if (source.rotation.size() == 4) {
            const std::vector<double>& q = source.rotation; // glTF order: x, y, z, w
            node.rotation = glm::dquat(q[3], q[0], q[1], q[2]);
        }
        if (source.scale.size() == 3) node.scale = glm::make_vec3(source.scale.data());
    }
    return nodes;
}

// Parents before children; build_gltf has checked that the hierarchy is a forest.
std::vector<std::size_t> hierarchy_order(const tinygltf::Model& model, const std::vector<int>& parent) {
    std::vector<std::size_t> order;
    order.reserve(parent.size());
    for (std::size_t i = 0; i < parent.size(); ++i) {
        if (parent[i] == -1) order.push_back(i);
    }
    for (std::size_t next = 0; next < order.size(); ++next) {
        for (int child : model.nodes[order[next]].children)
            order.push_back(static_cast<std::size_t>(child));
    }
    return order;
}

Result<std::vector<anim::Skin>> read_skins(const tinygltf::Model& model, std::size_t file_size) {
    using R = Result<std::vector<anim::Skin>>;
    std::vector<anim::Skin> skins(model.skins.size());
    for (std::size_t s = 0; s < skins.size(); ++s) {
        const tinygltf::Skin& source = model.skins[s];
        const std::string what = "skin " + std::to_string(s);
        if (source.joints.empty()) return R::failure(what + " has no joints");
        for (int joint : source.joints) {
            if (joint < 0 || static_cast<std::size_t>(joint) >= model.nodes.size()) {
                return R::failure(what + " refers to missing joint node " + std::to_string(joint));
            }
            skins[s].joints.push_back(static_cast<std::size_t>(joint));
        }
        if (source.inverseBindMatrices < 0) {
            skins[s].inverse_bind.assign(source.joints.size(), glm::dmat4(1.0));
            continue;
        }
        Result<std::vector<glm::dmat4>> matrices =
            read_matrices(model, source.inverseBindMatrices, file_size, what + " inverseBindMatrices");
        if (!matrices) return matrices.status();
        if (matrices->size() < source.joints.size()) {
            return R::failure(what + " has " + std::to_string(matrices->size()) +
                              " inverse bind matrices for " + std::to_string(source.joints.size()) +
                              " joints");
        }
        matrices->resize(source.joints.size());
        for (std::size_t j = 0; j < matrices->size(); ++j) {
            if (!finite((*matrices)[j])) {
                return R::failure(what + " inverse bind matrix " + std::to_string(j) + " is not finite");
            }
        }
        skins[s].inverse_bind = std::move(*matrices);
    }
    return skins;
}

bool has_attribute(const tinygltf::Primitive& primitive, const std::string& name) {
    return primitive.attributes.find(name) != primitive.attributes.end();
}

/// Appends the influences of the `count` vertices of a skinned vertex block: every JOINTS_n/WEIGHTS_n
/// pair of `primitive`, zero weights dropped (so their joint indices are not used), the rest normalised.
Status add_influences(const tinygltf::Model& model, std::size_t file_size,
                      const tinygltf::Primitive& primitive, std::uint32_t count, const anim::Skin& skin,
                      const std::string& where, anim::Influences& out) {
    std::vector<std::vector<glm::dvec4>> joints;
    std::vector<std::vector<glm::dvec4>> weights;
    for (std::size_t set = 0; has_attribute(primitive, "JOINTS_" + std::to_string(set)); ++set) {
        const std::string joint_name = "JOINTS_" + std::to_string(set);
        const std::string weight_name = "WEIGHTS_" + std::to_string(set);
        if (!has_attribute(primitive, weight_name)) {
            return Status::failure(joint_name + " without " + weight_name + " in " + where);
        }
        Result<std::vector<glm::dvec4>> j =
            read_vectors(model, primitive.attributes.at(joint_name), file_size, TINYGLTF_TYPE_VEC4, kJoints,
                         joint_name + " of " + where);
        if (!j) return j.status();
        Result<std::vector<glm::dvec4>> w =
            read_vectors(model, primitive.attributes.at(weight_name), file_size, TINYGLTF_TYPE_VEC4, kWeights,
                         weight_name + " of " + where);
        if (!w) return w.status();
        if (j->size() != count || w->size() != count) {
            return Status::failure(joint_name + " or " + weight_name + " of " + where + " has " +
                                   std::to_string(std::min(j->size(), w->size())) + " elements for " +
                                   std::to_string(count) + " vertices");
        }
        joints.push_back(std::move(*j));
        weights.push_back(std::move(*w));
    }
    for (std::uint32_t v = 0; v < count; ++v) {
        const std::size_t start = out.weight.size();
        double sum = 0.0;
        for (std::size_t set = 0; set < joints.size(); ++set) {
            for (int c = 0; c < 4; ++c) {
                const double weight = weights[set][v][c];
                if (!std::isfinite(weight) || weight < 0.0) {
                    return Status::failure("WEIGHTS_" + std::to_string(set) + " of " + where + ": vertex " +
                                           std::to_string(v) + " has weight " + std::to_string(weight) +
                                           " (must be finite and not negative)");
                }
                if (weight == 0.0) continue;
                const double joint = joints[set][v][c];
                if (joint >= static_cast<double>(skin.joints.size())) {
                    return Status::failure(
                        "JOINTS_" + std::to_string(set) + " of " + where + ": vertex " + std::to_string(v) +
                        " uses joint " + std::to_string(static_cast<std::uint64_t>(joint)) +
                        " but its skin has " + std::to_string(skin.joints.size()) + " joints");
                }
                out.joint.push_back(static_cast<std::uint32_t>(joint));
                out.weight.push_back(weight);
                sum += weight;
            }
        }
        // Exporters round weights, so their sum is often 1 only to a few digits; glTF asks for 1.
        for (std::size_t i = start; i < out.weight.size(); ++i)
            out.weight[i] /= sum;
        out.begin.push_back(static_cast<std::uint32_t>(out.weight.size()));
    }
    return {};
}

/// Whether `path` is a target an extension the file uses defines (KHR_animation_pointer's "pointer").
bool extension_target(const tinygltf::Model& model, const std::string& path) {
    const auto& used = model.extensionsUsed;
    return path == "pointer" && std::find(used.begin(), used.end(), "KHR_animation_pointer") != used.end();
}

Result<Interpolation> interpolation(const std::string& name, const std::string& where) {
    if (name == "LINEAR") return Interpolation::linear;
    if (name == "STEP") return Interpolation::step;
    if (name == "CUBICSPLINE") return Interpolation::cubic;
    return Result<Interpolation>::failure(where + " has unknown interpolation '" + name + "'");
}

Result<anim::Channel> read_channel(const tinygltf::Model& model, std::size_t file_size,
                                   const tinygltf::Animation& animation,
                                   const tinygltf::AnimationChannel& source, Path path,
                                   const std::string& where) {
    using R = Result<anim::Channel>;
    if (source.sampler < 0 || static_cast<std::size_t>(source.sampler) >= animation.samplers.size()) {
        return R::failure(where + " refers to missing sampler " + std::to_string(source.sampler));
    }
    const tinygltf::AnimationSampler& sampler = animation.samplers[static_cast<std::size_t>(source.sampler)];
    const std::string sampler_where = where + " sampler " + std::to_string(source.sampler);
    anim::Channel channel;
    channel.path = path;
    Result<Interpolation> mode = interpolation(sampler.interpolation, sampler_where);
    if (!mode) return mode.status();
    channel.interpolation = *mode;

    Result<std::vector<glm::dvec4>> input =
        read_vectors(model, sampler.input, file_size, TINYGLTF_TYPE_SCALAR, kFloat, sampler_where + " input");
    if (!input) return input.status();
    if (input->empty()) return R::failure(sampler_where + " has no keys");
    for (std::size_t k = 0; k < input->size(); ++k) {
        const double t = (*input)[k].x;
        if (!std::isfinite(t))
            return R::failure(sampler_where + " key " + std::to_string(k) + " time is not finite");
        if (k > 0 && t < channel.times.back()) {
            return R::failure(sampler_where + " key times decrease at key " + std::to_string(k));
        }
        channel.times.push_back(t);
    }

    const int type = path == Path::rotation ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3;
    Result<std::vector<glm::dvec4>> output =
        read_vectors(model, sampler.output, file_size, type, path == Path::rotation ? kRotations : kFloat,
                     sampler_where + " output");
    if (!output) return output.status();
    const std::size_t per_key = channel.interpolation == Interpolation::cubic ? 3 : 1;
    if (output->size() != per_key * channel.times.size()) {
        return R::failure(sampler_where + " has " + std::to_string(output->size()) + " output values for " +
                          std::to_string(channel.times.size()) + " keys" +
                          (per_key == 3 ? " (CUBICSPLINE needs 3 per key)" : ""));
    }
    for (std::size_t k = 0; k < output->size(); ++k) {
        if (!finite((*output)[k])) {
            return R::failure(sampler_where + " output value " + std::to_string(k) + " is not finite");
        }
    }
    // Exporters round quaternion keys (simple_skin stores 45 degrees as (0, 0, 0.383, 0.924)); slerp
    // between keys that are not unit length would not keep a constant angular speed.
    if (path == Path::rotation && channel.interpolation != Interpolation::cubic) {
        for (glm::dvec4& q : *output) {
            const double length = glm::length(q);
            if (length > 0.0) q /= length;
        }
    }
    channel.values = std::move(*output);
    return channel;
}

/// Fills the raw positions, the placement of every vertex block and the skin influences.
Status read_blocks(const tinygltf::Model& model, std::size_t file_size, const detail::GltfGeometry& geometry,
                   const std::vector<anim::Skin>& skins, std::vector<glm::vec3>& raw,
                   std::vector<anim::Block>& blocks, anim::Influences& influences) {
    raw.resize(geometry.mesh.positions.size());
    for (const detail::GltfVertexBlock& source : geometry.blocks) {
        const tinygltf::Node& node = model.nodes[static_cast<std::size_t>(source.node)];
        const tinygltf::Primitive& primitive = model.meshes[source.mesh].primitives[source.primitive];
        const std::string where = detail::primitive_name(model, source.mesh, source.primitive);
        anim::Block block;
        block.first = source.first;
        block.count = source.count;
        block.node = static_cast<std::size_t>(source.node);

        Result<std::vector<glm::vec3>> positions = detail::read_accessor<glm::vec3>(
            model, primitive.attributes.at("POSITION"), file_size, [](const unsigned char* p) {
                glm::vec3 v;
                std::memcpy(&v, p, sizeof v);
                return v;
            });
        if (!positions) return Status::failure(positions.message() + " in " + where);
        std::copy(positions->begin(), positions->end(), raw.begin() + source.first);

        if (node.skin >= 0) {
            if (static_cast<std::size_t>(node.skin) >= skins.size()) {
                return Status::failure("node " + std::to_string(source.node) + " refers to missing skin " +
                                       std::to_string(node.skin));
            }
            block.skin = static_cast<std::size_t>(node.skin);
            block.placement =
                has_attribute(primitive, "JOINTS_0") ? anim::Placement::skin : anim::Placement::fixed;
        }
        if (block.placement == anim::Placement::skin) {
            if (Status status = add_influences(model, file_size, primitive, block.count, skins[block.skin],
                                               where, influences);
                !status) {
                return status;
            }
        } else {
            influences.begin.insert(influences.begin.end(), block.count, influences.begin.back());
        }
        blocks.push_back(block);
    }
    return {};
}

} // namespace

Result<std::vector<anim::Clip>> detail::anim::read_clips(const tinygltf::Model& model, std::size_t file_size,
                                                         const std::vector<anim::Node>& nodes) {
    using R = Result<std::vector<anim::Clip>>;
    std::vector<anim::Clip> clips(model.animations.size());
    for (std::size_t a = 0; a < clips.size(); ++a) {
        const tinygltf::Animation& animation = model.animations[a];
        anim::Clip& clip = clips[a];
        clip.name = clip_name(model, a);
        for (std::size_t c = 0; c < animation.channels.size(); ++c) {
            const tinygltf::AnimationChannel& source = animation.channels[c];
            const std::string where = "animation '" + clip.name + "' channel " + std::to_string(c);
            Path path;
            if (source.target_path == "translation") {
                path = Path::translation;
            } else if (source.target_path == "rotation") {
                path = Path::rotation;
            } else if (source.target_path == "scale") {
                path = Path::scale;
            } else if (source.target_path.empty()) {
                // glTF requires the path (and the target): an exporter's slip, which froze the clip silently.
                return R::failure(where + " has no target path (glTF requires target.path)");
            } else if (source.target_path == "weights" || extension_target(model, source.target_path)) {
                continue; // morph target weights and extension-defined targets do not move vertices here
            } else {
                // Anything else is a typo that would leave the clip frozen without a word.
                return R::failure(where + " has unknown target path '" + source.target_path +
                                  "' (glTF allows translation, rotation, scale and weights)");
            }
            // glTF lets an extension name the target instead of a node.
            if (source.target_node < 0) continue;
            const auto node = static_cast<std::size_t>(source.target_node);
            if (node >= nodes.size()) {
                return R::failure(where + " targets missing node " + std::to_string(source.target_node));
            }
            if (nodes[node].has_matrix) {
                return R::failure(where + " targets node " + std::to_string(node) +
                                  ", which has a matrix (glTF allows animating TRS nodes only)");
            }
            Result<anim::Channel> channel = read_channel(model, file_size, animation, source, path, where);
            if (!channel) return channel.status();
            const auto slot = std::find(clip.targets.begin(), clip.targets.end(), node);
            channel->slot = static_cast<std::size_t>(slot - clip.targets.begin());
            if (slot == clip.targets.end()) clip.targets.push_back(node);
            clip.duration = std::max(clip.duration, channel->times.back());
            clip.channels.push_back(std::move(*channel));
        }
    }
    return clips;
}

Result<anim::Rig> detail::anim::read_rig(const tinygltf::Model& model, std::size_t file_size,
                                         detail::GltfGeometry& geometry) {
    Result<std::vector<anim::Skin>> skins = read_skins(model, file_size);
    if (!skins) return skins.status();
    anim::Rig rig;
    rig.nodes = read_nodes(model);
    if (Status status = read_blocks(model, file_size, geometry, *skins, rig.raw, rig.blocks, rig.influences);
        !status) {
        return status;
    }
    rig.hierarchy_order = hierarchy_order(model, geometry.parent);
    rig.parent = std::move(geometry.parent);
    rig.walk_order = std::move(geometry.walk_order);
    rig.walk_parent = std::move(geometry.walk_parent);
    rig.skins = std::move(*skins);
    rig.skinned = std::any_of(rig.blocks.begin(), rig.blocks.end(),
                              [](const anim::Block& b) { return b.placement == anim::Placement::skin; });
    return rig;
}

} // namespace gust
