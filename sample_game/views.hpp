// Which of the sample's views are on: the keys and the tour's shots both set them.
#pragma once

#include <string>

namespace sample {

/// What the views show; keys toggle them (docs/sample.md).
struct Views {
    bool triangles = true;     ///< Q: the solid meshes
    bool grass = true;         ///< G: the grass blades
    bool voxels = false;       ///< W: gust's voxels (their faces that meet empty space)
    bool nodes = false;        ///< R: tree node boxes, coloured by this frame's refine and coarsen
    bool every_node = true;    ///< R draws every node; off: only those moving meshes reach, made or freed
    bool slice = false;        ///< T: wind speed on a horizontal slice
    bool arrows = false;       ///< Y: wind arrows on the slice
    bool cascades = false;     ///< each wind cascade's extent as a box (the tour's valley shot)
    float slice_height = 1.0f; ///< world y of the slice and the arrows, m
};

/// The views as --views and stats.jsonl spell them: the letters of the keys that changed them from the
/// defaults (q: triangles hidden, g: grass hidden, w, r, t, y: on).
inline std::string view_letters(const Views& views) {
    std::string letters;
    if (!views.triangles) letters += 'q';
    if (!views.grass) letters += 'g';
    if (views.voxels) letters += 'w';
    if (views.nodes) letters += 'r';
    if (views.slice) letters += 't';
    if (views.arrows) letters += 'y';
    return letters;
}

} // namespace sample
