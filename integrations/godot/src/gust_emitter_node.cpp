// GustEmitter: a Spatial child of GustWind that blows. Its position is the emitter's, its -Z axis (Godot's
// forward) the flow direction or a vortex's axis.
#include "nodes.hpp"

#include <cmath>

namespace gust::godot {

namespace {

constexpr char kClass[] = "GustEmitter";
const int kTypeTag = 0; // its address tags GustEmitter instances

struct Emitter {
    godot_object* owner = nullptr;
    std::int64_t type = 4; // WindEmitterType::ConeMotor: a fan
    double radius = 1.0;
    double strength = 5.0;
    double falloff = 1.0;
    double length = 4.0;
    bool enabled = true;
};

Emitter& self(void* user) {
    return *static_cast<Emitter*>(user);
}

// Property setters keep the old value and log why when the new one is invalid.
bool check(bool ok, const std::string& message) {
    if (!ok) {
        error("GustEmitter." + message, "GustEmitter");
    }
    return ok;
}

void set_type(godot_object*, void*, void* u, godot_variant* v) {
    const std::int64_t t = core->godot_variant_as_int(v);
    if (check(t >= 0 && t <= 4,
              "type = " + std::to_string(t) +
                  ": must be 0 (directional), 1 (omni), 2 (vortex), 3 (capsule motor) or 4 (cone motor)")) {
        self(u).type = t;
    }
}
void set_radius(godot_object*, void*, void* u, godot_variant* v) {
    const double r = core->godot_variant_as_real(v);
    if (check(std::isfinite(r) && r > 0.0, "radius = " + std::to_string(r) + ": must be a length > 0 m")) {
        self(u).radius = r;
    }
}
void set_strength(godot_object*, void*, void* u, godot_variant* v) {
    const double s = core->godot_variant_as_real(v);
    if (check(std::isfinite(s), "strength must be finite (m/s)")) {
        self(u).strength = s;
    }
}
void set_falloff(godot_object*, void*, void* u, godot_variant* v) {
    const double f = core->godot_variant_as_real(v);
    if (check(std::isfinite(f) && f >= 0.0, "falloff = " + std::to_string(f) + ": must be >= 0")) {
        self(u).falloff = f;
    }
}
void set_length(godot_object*, void*, void* u, godot_variant* v) {
    const double l = core->godot_variant_as_real(v);
    if (check(std::isfinite(l) && l >= 0.0, "length = " + std::to_string(l) + ": must be >= 0 m")) {
        self(u).length = l;
    }
}
void set_enabled(godot_object*, void*, void* u, godot_variant* v) {
    self(u).enabled = core->godot_variant_as_bool(v);
}

godot_variant get_type(godot_object*, void*, void* u) {
    return Var(self(u).type).release();
}
godot_variant get_radius(godot_object*, void*, void* u) {
    return Var(self(u).radius).release();
}
godot_variant get_strength(godot_object*, void*, void* u) {
    return Var(self(u).strength).release();
}
godot_variant get_falloff(godot_object*, void*, void* u) {
    return Var(self(u).falloff).release();
}
godot_variant get_length(godot_object*, void*, void* u) {
    return Var(self(u).length).release();
}
godot_variant get_enabled(godot_object*, void*, void* u) {
    return Var(self(u).enabled).release();
}

} // namespace

bool emitter_of(godot_object* object, WindEmitter& out) {
    auto* e = static_cast<Emitter*>(userdata_if(object, &kTypeTag));
    if (e == nullptr || !e->enabled) {
        return false;
    }
    float m[16];
    to_column_major(call(object, "Spatial", "get_global_transform").as_transform(), m);
    float dx = -m[8], dy = -m[9], dz = -m[10];
    const float len = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(len > 0.0f) || !std::isfinite(len)) {
        return false;
    }
    out.type = WindEmitterType(e->type);
    out.position = {m[12], m[13], m[14]};
    out.direction = {dx / len, dy / len, dz / len};
    out.radius = float(e->radius);
    out.strength = float(e->strength);
    out.falloff = float(e->falloff);
    out.length = float(e->length);
    return true;
}

void register_gust_emitter(void* handle) {
    godot_instance_create_func create{};
    create.create_func = [](godot_object* owner, void*) -> void* {
        auto* e = new Emitter;
        e->owner = owner;
        return e;
    };
    godot_instance_destroy_func destroy{};
    destroy.destroy_func = [](godot_object*, void*, void* u) { delete static_cast<Emitter*>(u); };
    nativescript->godot_nativescript_register_class(handle, kClass, "Spatial", create, destroy);
    nativescript11->godot_nativescript_set_type_tag(handle, kClass, &kTypeTag);
    register_property(handle, kClass, "type", Var(std::int64_t(4)), GODOT_PROPERTY_HINT_ENUM,
                      "Directional,Omni,Vortex,CapsuleMotor,ConeMotor", set_type, get_type);
    register_property(handle, kClass, "radius", Var(1.0), GODOT_PROPERTY_HINT_NONE, "", set_radius,
                      get_radius);
    register_property(handle, kClass, "strength", Var(5.0), GODOT_PROPERTY_HINT_NONE, "", set_strength,
                      get_strength);
    register_property(handle, kClass, "falloff", Var(1.0), GODOT_PROPERTY_HINT_NONE, "", set_falloff,
                      get_falloff);
    register_property(handle, kClass, "length", Var(4.0), GODOT_PROPERTY_HINT_NONE, "", set_length,
                      get_length);
    register_property(handle, kClass, "enabled", Var(true), GODOT_PROPERTY_HINT_NONE, "", set_enabled,
                      get_enabled);
}

} // namespace gust::godot
