// The extension's nodes: GustWind3D (Node3D) and GustEmitter3D (Node3D), with the properties and methods
// docs/godot.md lists.
#pragma once

namespace gust::godot4 {

/// Registers GustWind3D and GustEmitter3D with ClassDB (at the scene level's initialization).
void register_nodes();

} // namespace gust::godot4
