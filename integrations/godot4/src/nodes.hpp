// The extension's nodes: GustWind3D (Node3D) and GustEmitter3D (Node3D), with the properties and methods
// docs/godot.md lists.
#pragma once

namespace gust::godot4 {

/// Registers GustWind3D and GustEmitter3D with ClassDB (at the scene level's initialization).
void register_nodes();
/// Destroys Godot's images over gust's exported wind copies that are still kept for Godot's frames in
/// flight, after waiting for Godot's device (at the scene level's deinitialization, after the main loop).
void release_godot_images();

} // namespace gust::godot4
