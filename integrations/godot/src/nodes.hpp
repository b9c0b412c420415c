// The two NativeScript classes of the plugin (docs/godot.md).
#pragma once

#include "godot_api.hpp"

#include <gust/gust.hpp>

namespace gust::godot {

/// Registers GustWind (Spatial) with its GustSampler (Reference), and GustEmitter (Spatial), with
/// NativeScript.
void register_gust_wind(void* handle);
void register_gust_emitter(void* handle);

/// The GustEmitter behind `object` as a gust emitter in world space; false when `object` is no enabled
/// GustEmitter.
bool emitter_of(godot_object* object, WindEmitter& out);

} // namespace gust::godot
