// Where the moving things of the sample's world are this frame, as cameras need them.
#pragma once

#include <glm/glm.hpp>
#include <vector>

namespace sample {

/// A moving thing: where it is and where it heads (world, m; `forward` is a horizontal unit vector).
struct Actor {
    glm::vec3 position{0.0f}; ///< its feet (walkers) or its centre (the flyer)
    glm::vec3 forward{0.0f, 0.0f, 1.0f};
};

/// A world-space box that a camera should not look through (a building or a tree).
struct Obstacle {
    glm::vec3 lo{0.0f}, hi{0.0f}; ///< corners, m
};

/// The actors the tour films (World::stage).
struct Stage {
    Actor fox;                           ///< walking a circle through the grass
    Actor walker;                        ///< CesiumMan, walking an ellipse
    Actor flyer;                         ///< the bunny with a motor, flying a figure of eight
    glm::vec3 fan{0.0f};                 ///< the fan's head
    glm::vec3 ridge_grove{0.0f};         ///< middle of the grove on the ridge's crest, on the ground
    glm::vec3 lee_grove{0.0f};           ///< middle of the grove in the ridge's lee, on the ground
    glm::vec3 upwind{-1.0f, 0.0f, 0.0f}; ///< horizontal unit vector from the village towards the ridge
    std::vector<Obstacle> obstacles;     ///< the bounds of what stands still and hides what is behind it
};

} // namespace sample
