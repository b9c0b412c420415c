// The sample's camera: an orbit around a target, which a person drags and the tour directs.
#pragma once

#include <cmath>
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

namespace sample {

/// An eye on a sphere around `target` (world, m; angles in radians).
struct OrbitCamera {
    glm::vec3 target{0.0f, 1.0f, 0.0f}; ///< what the eye looks at (world, m)
    float yaw = 2.4f;                   ///< direction from the target to the eye, about +y from +x
    float pitch = 0.38f;                ///< height of the eye above the target's horizon
    float distance = 19.0f;             ///< from the target to the eye, m
    float fov_deg = 55.0f;              ///< vertical field of view

    /// Where the eye is (world, m).
    glm::vec3 eye() const {
        return target + distance * glm::vec3(std::cos(pitch) * std::cos(yaw), std::sin(pitch),
                                             std::cos(pitch) * std::sin(yaw));
    }
    /// Projection times view for a target of `aspect` (width over height), Vulkan's clip space.
    glm::mat4 view_proj(float aspect) const {
        glm::mat4 proj = glm::perspectiveRH_ZO(glm::radians(fov_deg), aspect, 0.1f, 2500.0f);
        proj[1][1] *= -1.0f; // Vulkan's clip space has y down
        return proj * glm::lookAt(eye(), target, glm::vec3(0, 1, 0));
    }
};

} // namespace sample
