// SceneRuntime: one load per mesh file (terrains generated), then each object's matrix and (posed) positions
// on demand.
#include "gust/scene/scene_runtime.hpp"

#include "gust/scene/import.hpp"
#include "gust/scene/primitives.hpp"

#include <cassert>
#include <cmath>
#include <exception>
#include <map>
#include <new>
#include <string>
#include <utility>

namespace gust {
namespace {

std::string object_key(const SceneDesc& scene, std::size_t object, const char* key) {
    return scene.file.string() + ": objects[" + std::to_string(object) + "]." + key + ": ";
}

std::string list(const std::vector<std::string>& names) {
    std::string text;
    for (const std::string& name : names)
        text += (text.empty() ? "" : ", ") + name;
    return text.empty() ? "the file has no clips" : "clips: " + text;
}

} // namespace

Result<SceneRuntime> SceneRuntime::load(const SceneDesc& scene) {
    using R = Result<SceneRuntime>;
    try {
        // A file that any object animates is loaded as an AnimatedMesh, and every object using that
        // file shares its rest pose, so that one file is read and triangulated once.
        std::map<std::filesystem::path, std::shared_ptr<const AnimatedMesh>> animated;
        for (std::size_t i = 0; i < scene.objects.size(); ++i) {
            const SceneObject& object = scene.objects[i];
            if (!object.animation || animated.contains(object.mesh)) continue;
            Result<AnimatedMesh> mesh = AnimatedMesh::load(object.mesh);
            if (!mesh) return R::failure(object_key(scene, i, "mesh") + mesh.message());
            animated.emplace(object.mesh, std::make_shared<const AnimatedMesh>(std::move(*mesh)));
        }
        std::map<std::filesystem::path, std::shared_ptr<const Mesh>> meshes;
        for (const auto& [path, mesh] : animated)
            meshes.emplace(path, std::shared_ptr<const Mesh>(mesh, &mesh->rest_pose()));

        SceneRuntime runtime;
        for (std::size_t i = 0; i < scene.objects.size(); ++i) {
            const SceneObject& desc = scene.objects[i];
            Object object;
            object.desc = desc;
            if (desc.terrain) {
                // Generated per object: scenes hold one terrain or a few different ones.
                object.mesh = std::make_shared<const Mesh>(make_terrain_mesh(*desc.terrain));
                runtime.objects_.push_back(std::move(object));
                continue;
            }
            auto mesh = meshes.find(desc.mesh);
            if (mesh == meshes.end()) {
                Result<Mesh> loaded = load_mesh(desc.mesh);
                if (!loaded) return R::failure(object_key(scene, i, "mesh") + loaded.message());
                mesh = meshes.emplace(desc.mesh, std::make_shared<const Mesh>(std::move(*loaded))).first;
            }
            object.mesh = mesh->second;
            if (desc.animation) {
                object.animated = animated.at(desc.mesh);
                const std::optional<std::size_t> clip = object.animated->find_clip(desc.animation->clip);
                if (!clip) {
                    return R::failure(object_key(scene, i, "animation.clip") + "no clip '" +
                                      desc.animation->clip + "' in " + desc.mesh.string() + " (" +
                                      list(object.animated->clip_names()) + ")");
                }
                object.clip = *clip;
            }
            runtime.objects_.push_back(std::move(object));
        }
        return runtime;
    } catch (const std::bad_alloc&) {
        return R::failure(scene.file.string() + ": out of memory");
    } catch (const std::exception& e) {
        return R::failure(scene.file.string() + ": unexpected error: " + e.what());
    }
}

std::size_t SceneRuntime::object_count() const {
    return objects_.size();
}

const Mesh& SceneRuntime::mesh(std::size_t object) const {
    assert(object < objects_.size());
    return *objects_[object].mesh;
}

bool SceneRuntime::deforms(std::size_t object) const {
    assert(object < objects_.size());
    return objects_[object].animated != nullptr;
}

glm::mat4 SceneRuntime::model(std::size_t object, double t) const {
    assert(object < objects_.size());
    return object_matrix(objects_[object].desc, t);
}

bool SceneRuntime::jumps(std::size_t object, double t0, double t1) const {
    assert(object < objects_.size());
    const Object& o = objects_[object];
    if (object_jumps(o.desc, t0, t1)) return true;
    if (!o.animated || !o.desc.animation->loop) return false;
    const double duration = o.animated->clip_duration(o.clip);
    if (!(duration > 0.0)) return false;
    const AnimationDesc& animation = *o.desc.animation;
    // The clip wraps between the two clip times when they lie in different laps of it.
    const double lap0 = std::floor((animation.offset + animation.speed * t0) / duration);
    const double lap1 = std::floor((animation.offset + animation.speed * t1) / duration);
    return lap0 != lap1;
}

const std::vector<glm::vec3>& SceneRuntime::positions(std::size_t object, double t) {
    assert(object < objects_.size());
    Object& o = objects_[object];
    if (!o.animated) return o.mesh->positions;
    const AnimationDesc& animation = *o.desc.animation;
    o.animated->pose(o.clip, animation.offset + animation.speed * t, animation.loop, o.posed);
    return o.posed;
}

} // namespace gust
