// glTF animation playback: node TRS channels (LINEAR with slerp for rotations, STEP, CUBICSPLINE)
// evaluated down the node hierarchy, then linear-blend skinning as the glTF 2.0 specification defines
// it (section 3.7.3): joint matrix = global transform of the joint · inverse bind matrix, vertex =
// sum of weight · joint matrix · POSITION, the skinned mesh node's own transform ignored.
#include "gust/scene/animated_mesh.hpp"

#include "gltf_rig.hpp"
#include "import_detail.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <glm/gtc/quaternion.hpp>
#include <new>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust {

namespace anim = detail::anim;

struct AnimatedMesh::Data {
    Mesh bind; ///< the triangles, positions in the rest pose
    anim::Rig rig;
    std::vector<anim::Clip> clips;
};

namespace {

using anim::Interpolation;
using anim::Path;

std::vector<glm::dmat4> rest_locals(const anim::Rig& rig) {
    std::vector<glm::dmat4> local(rig.nodes.size());
    for (std::size_t n = 0; n < rig.nodes.size(); ++n)
        local[n] = rig.nodes[n].rest;
    return local;
}

/// What moves the vertices for the nodes' local transforms: the walk's transform of every node (rigid
/// meshes) and every skin's joint matrices.
struct Placements {
    std::vector<glm::dmat4> walk;
    std::vector<std::vector<glm::dmat4>> joints;
};

// Joints are placed by the file's hierarchy; rigid meshes by the same walk that built the geometry, with the
// same arithmetic, so that the rest pose of an unskinned file reproduces build_gltf's positions exactly.
Placements placements(const anim::Rig& rig, const std::vector<glm::dmat4>& local) {
    std::vector<glm::dmat4> global(rig.nodes.size());
    for (std::size_t n : rig.hierarchy_order) {
        const int p = rig.parent[n];
        global[n] = p < 0 ? local[n] : global[static_cast<std::size_t>(p)] * local[n];
    }
    Placements out;
    out.walk.resize(rig.nodes.size());
    for (int node : rig.walk_order) {
        const auto n = static_cast<std::size_t>(node);
        const int from = rig.walk_parent[n];
        out.walk[n] = (from < 0 ? glm::dmat4(1.0) : out.walk[static_cast<std::size_t>(from)]) * local[n];
    }
    out.joints.resize(rig.skins.size());
    for (std::size_t s = 0; s < rig.skins.size(); ++s) {
        const anim::Skin& skin = rig.skins[s];
        for (std::size_t j = 0; j < skin.joints.size(); ++j)
            out.joints[s].push_back(global[skin.joints[j]] * skin.inverse_bind[j]);
    }
    return out;
}

/// Where AnimatedMesh::bone_skin's palette puts each matrix: every skin's joints in turn, then one entry
/// for each rigidly placed (walk) block, then the identity (fixed blocks, vertices without weights).
struct PaletteLayout {
    std::vector<std::size_t> skin_first; ///< per skin
    std::vector<std::size_t> block;      ///< per block: its entry (walk blocks) or the identity's
    std::size_t identity = 0;
    std::size_t size = 0;
};

PaletteLayout palette_layout(const anim::Rig& rig) {
    PaletteLayout out;
    for (const anim::Skin& skin : rig.skins) {
        out.skin_first.push_back(out.size);
        out.size += skin.joints.size();
    }
    for (const anim::Block& block : rig.blocks)
        out.block.push_back(block.placement == anim::Placement::walk ? out.size++ : 0);
    out.identity = out.size++;
    for (std::size_t b = 0; b < rig.blocks.size(); ++b)
        if (rig.blocks[b].placement != anim::Placement::walk) out.block[b] = out.identity;
    return out;
}

// Every vertex placed by the nodes' local transforms `local`.
void place(const anim::Rig& rig, const std::vector<glm::dmat4>& local, std::vector<glm::vec3>& out) {
    const Placements placed = placements(rig, local);
    const std::vector<glm::dmat4>& walk = placed.walk;
    const std::vector<std::vector<glm::dmat4>>& joints = placed.joints;

    out.resize(rig.raw.size());
    const anim::Influences& influences = rig.influences;
    for (const anim::Block& block : rig.blocks) {
        const std::uint32_t end = block.first + block.count;
        switch (block.placement) {
        case anim::Placement::walk:
            for (std::uint32_t v = block.first; v < end; ++v)
                out[v] = glm::vec3(walk[block.node] * glm::dvec4(rig.raw[v], 1.0));
            break;
        case anim::Placement::fixed:
            std::copy(rig.raw.begin() + block.first, rig.raw.begin() + end, out.begin() + block.first);
            break;
        case anim::Placement::skin:
            for (std::uint32_t v = block.first; v < end; ++v) {
                const std::uint32_t first = influences.begin[v];
                const std::uint32_t last = influences.begin[v + 1];
                if (first == last) {
                    out[v] = rig.raw[v]; // all weights zero: nothing to follow
                    continue;
                }
                glm::dmat4 blend(0.0);
                for (std::uint32_t i = first; i < last; ++i)
                    blend += influences.weight[i] * joints[block.skin][influences.joint[i]];
                out[v] = glm::vec3(blend * glm::dvec4(rig.raw[v], 1.0));
            }
            break;
        }
    }
}

double clip_time(double t, double duration, bool loop) {
    if (!std::isfinite(t)) return 0.0;
    if (!loop || duration <= 0.0) return t;
    double wrapped = std::fmod(t, duration);
    if (wrapped < 0.0) wrapped += duration;
    return wrapped;
}

glm::dquat to_quat(const glm::dvec4& v) {
    return glm::dquat(v.w, v.x, v.y, v.z);
}

/// The channel's value at time `t` (seconds), holding its first and last keys outside their range.
glm::dvec4 sample(const anim::Channel& channel, double t) {
    const std::vector<double>& times = channel.times;
    const bool cubic = channel.interpolation == Interpolation::cubic;
    auto value = [&](std::size_t k) { return channel.values[cubic ? 3 * k + 1 : k]; };
    if (!(t > times.front())) return value(0);
    if (t >= times.back()) return value(times.size() - 1);
    const auto k =
        static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), t) - times.begin() - 1);
    const double span = times[k + 1] - times[k]; // > 0: times[k] <= t < times[k + 1]
    const double s = (t - times[k]) / span;
    switch (channel.interpolation) {
    case Interpolation::step:
        return value(k);
    case Interpolation::linear:
        if (channel.path == Path::rotation) {
            const glm::dquat q = glm::slerp(to_quat(value(k)), to_quat(value(k + 1)), s);
            return {q.x, q.y, q.z, q.w};
        }
        return glm::mix(value(k), value(k + 1), s);
    case Interpolation::cubic: {
        // glTF 2.0, appendix C: Hermite spline with tangents scaled by the key interval.
        const double s2 = s * s;
        const double s3 = s2 * s;
        const glm::dvec4& out_tangent = channel.values[3 * k + 2];
        const glm::dvec4& in_tangent = channel.values[3 * (k + 1)];
        return (2 * s3 - 3 * s2 + 1) * value(k) + (s3 - 2 * s2 + s) * span * out_tangent +
               (-2 * s3 + 3 * s2) * value(k + 1) + (s3 - s2) * span * in_tangent;
    }
    }
    return value(k);
}

} // namespace

Result<AnimatedMesh> AnimatedMesh::load(const std::filesystem::path& gltf_or_glb) {
    using Loaded = Result<std::shared_ptr<const Data>>;
    // A lambda, not a free function: it may name the private Data.
    auto read = [&gltf_or_glb]() -> Loaded {
        Result<detail::MeshFile> file = detail::read_mesh_file(gltf_or_glb);
        if (!file) return file.status();
        if (!file->gltf()) {
            return Loaded::failure("animation needs a glTF file (.gltf or .glb), not '" + file->extension +
                                   "'");
        }
        const std::size_t file_size = file->bytes.size();
        Result<tinygltf::Model> model = detail::parse_gltf(file->bytes, gltf_or_glb);
        if (!model) return model.status();
        Result<detail::GltfGeometry> geometry = detail::build_gltf(*model, file_size);
        if (!geometry) return geometry.status();
        Result<anim::Rig> rig = anim::read_rig(*model, file_size, *geometry);
        if (!rig) return rig.status();
        Result<std::vector<anim::Clip>> clips = anim::read_clips(*model, file_size, rig->nodes);
        if (!clips) return clips.status();

        auto data = std::make_shared<Data>();
        data->bind = std::move(geometry->mesh);
        data->bind.name = gltf_or_glb.filename().string();
        if (rig->skinned) place(*rig, rest_locals(*rig), data->bind.positions);
        data->rig = std::move(*rig);
        data->clips = std::move(*clips);
        return std::shared_ptr<const Data>(std::move(data));
    };
    std::string reason;
    try {
        Loaded data = read();
        if (data) return AnimatedMesh(std::move(*data));
        reason = data.message();
    } catch (const std::bad_alloc&) {
        reason = "out of memory";
    } catch (const std::exception& e) {
        reason = "unexpected error: " + detail::clean_message(e.what());
    }
    return Result<AnimatedMesh>::failure(gltf_or_glb.string() + ": " + reason);
}

const Mesh& AnimatedMesh::rest_pose() const {
    return data_->bind;
}

std::vector<std::string> AnimatedMesh::clip_names() const {
    std::vector<std::string> names;
    for (const anim::Clip& clip : data_->clips)
        names.push_back(clip.name);
    return names;
}

std::optional<std::size_t> AnimatedMesh::find_clip(const std::string& name) const {
    for (std::size_t i = 0; i < data_->clips.size(); ++i) {
        if (data_->clips[i].name == name) return i;
    }
    return std::nullopt;
}

double AnimatedMesh::clip_duration(std::size_t clip) const {
    return clip < data_->clips.size() ? data_->clips[clip].duration : 0.0;
}

bool AnimatedMesh::skinned() const {
    return data_->rig.skinned;
}

Result<AnimatedMesh::BoneSkin> AnimatedMesh::bone_skin() const {
    const anim::Rig& rig = data_->rig;
    const PaletteLayout layout = palette_layout(rig);
    if (layout.size > kMaxBones)
        return Result<BoneSkin>::failure("the palette would need " + std::to_string(layout.size) +
                                         " matrices, more than " + std::to_string(kMaxBones));
    BoneSkin out;
    out.bind = rig.raw;
    out.joint_count = static_cast<std::uint32_t>(layout.size);
    out.joints.assign(4 * rig.raw.size(), static_cast<std::uint16_t>(layout.identity));
    out.weights.assign(4 * rig.raw.size(), 0.0f);
    const anim::Influences& influences = rig.influences;
    for (std::size_t b = 0; b < rig.blocks.size(); ++b) {
        const anim::Block& block = rig.blocks[b];
        for (std::uint32_t v = block.first; v < block.first + block.count; ++v) {
            const std::uint32_t first = influences.begin[v], last = influences.begin[v + 1];
            if (block.placement != anim::Placement::skin || first == last) {
                out.joints[4 * v] = static_cast<std::uint16_t>(layout.block[b]);
                out.weights[4 * v] = 1.0f;
                continue;
            }
            if (last - first > 4)
                return Result<BoneSkin>::failure("vertex " + std::to_string(v) + " follows " +
                                                 std::to_string(last - first) + " joints, more than 4");
            for (std::uint32_t i = first; i < last; ++i) {
                out.joints[4 * v + (i - first)] =
                    static_cast<std::uint16_t>(layout.skin_first[block.skin] + influences.joint[i]);
                out.weights[4 * v + (i - first)] = static_cast<float>(influences.weight[i]);
            }
        }
    }
    return out;
}

void AnimatedMesh::bone_palette(std::size_t clip, double t, bool loop, std::vector<glm::mat4>& out) const {
    const anim::Rig& rig = data_->rig;
    const Placements placed = placements(rig, locals_at(clip, t, loop));
    const PaletteLayout layout = palette_layout(rig);
    out.assign(layout.size, glm::mat4(1.0f));
    for (std::size_t s = 0; s < rig.skins.size(); ++s)
        for (std::size_t j = 0; j < placed.joints[s].size(); ++j)
            out[layout.skin_first[s] + j] = glm::mat4(placed.joints[s][j]);
    for (std::size_t b = 0; b < rig.blocks.size(); ++b)
        if (rig.blocks[b].placement == anim::Placement::walk)
            out[layout.block[b]] = glm::mat4(placed.walk[rig.blocks[b].node]);
}

void AnimatedMesh::pose(std::size_t clip, double t, bool loop, std::vector<glm::vec3>& out) const {
    place(data_->rig, locals_at(clip, t, loop), out);
}

std::vector<glm::dmat4> AnimatedMesh::locals_at(std::size_t clip, double t, bool loop) const {
    const Data& d = *data_;
    std::vector<glm::dmat4> local = rest_locals(d.rig);
    if (clip < d.clips.size()) {
        const anim::Clip& c = d.clips[clip];
        const double time = clip_time(t, c.duration, loop);
        struct Trs {
            glm::dvec3 translation;
            glm::dquat rotation;
            glm::dvec3 scale;
        };
        std::vector<Trs> trs;
        trs.reserve(c.targets.size());
        for (std::size_t node : c.targets) {
            const anim::Node& rest = d.rig.nodes[node];
            trs.push_back({rest.translation, rest.rotation, rest.scale});
        }
        for (const anim::Channel& channel : c.channels) {
            const glm::dvec4 v = sample(channel, time);
            Trs& target = trs[channel.slot];
            switch (channel.path) {
            case Path::translation:
                target.translation = glm::dvec3(v);
                break;
            case Path::rotation:
                target.rotation = to_quat(v);
                break;
            case Path::scale:
                target.scale = glm::dvec3(v);
                break;
            }
        }
        for (std::size_t i = 0; i < c.targets.size(); ++i)
            local[c.targets[i]] = detail::trs_matrix(trs[i].translation, trs[i].rotation, trs[i].scale);
    }
    return local;
}

namespace detail {

Result<Mesh> gltf_rest_pose(const tinygltf::Model& model, std::size_t file_size) {
    Result<GltfGeometry> geometry = build_gltf(model, file_size);
    if (!geometry) return geometry.status();
    Result<anim::Rig> rig = anim::read_rig(model, file_size, *geometry);
    if (!rig) return rig.status();
    if (rig->skinned) place(*rig, rest_locals(*rig), geometry->mesh.positions);
    return std::move(geometry->mesh);
}

} // namespace detail

} // namespace gust
