// Thin C++ helpers over Godot 3's GDNative C API: the API tables, owned Variants, method calls by name and
// error reporting into Godot's log. Everything else of the plugin calls Godot through these.
#pragma once

#include <cstdint>
#include <gdnative_api_struct.gen.h>
#include <initializer_list>
#include <string>
#include <vector>

namespace gust::godot {

/// The tables Godot handed to godot_gdnative_init (valid until godot_gdnative_terminate).
extern const godot_gdnative_core_api_struct* core;
extern const godot_gdnative_ext_nativescript_api_struct* nativescript;
extern const godot_gdnative_ext_nativescript_1_1_api_struct* nativescript11;

/// Godot's log: "ERROR: <where>: <message>" (and a push to the debugger), from any thread.
void error(const std::string& message, const char* where);
void warning(const std::string& message, const char* where);

/// An owned godot_variant (destroyed with it).
class Var {
  public:
    Var() { core->godot_variant_new_nil(&v_); }
    explicit Var(const godot_variant& take) : v_(take) {} ///< takes ownership of a returned variant
    explicit Var(bool b) { core->godot_variant_new_bool(&v_, b); }
    explicit Var(std::int64_t i) { core->godot_variant_new_int(&v_, i); }
    explicit Var(double r) { core->godot_variant_new_real(&v_, r); }
    explicit Var(const char* s);
    explicit Var(godot_object* o) { core->godot_variant_new_object(&v_, o); }
    explicit Var(const godot_vector3& v) { core->godot_variant_new_vector3(&v_, &v); }
    explicit Var(const godot_transform& t) { core->godot_variant_new_transform(&v_, &t); }
    Var(const Var& o) { core->godot_variant_new_copy(&v_, &o.v_); }
    Var& operator=(const Var& o);
    ~Var() { core->godot_variant_destroy(&v_); }

    const godot_variant* get() const { return &v_; }
    godot_variant release(); ///< hands the variant to the caller (this becomes nil)
    godot_variant_type type() const { return core->godot_variant_get_type(&v_); }
    bool is_nil() const { return type() == GODOT_VARIANT_TYPE_NIL; }
    godot_object* object() const; ///< null unless an object
    std::int64_t as_int() const { return core->godot_variant_as_int(&v_); }
    double as_real() const { return core->godot_variant_as_real(&v_); }
    bool as_bool() const { return core->godot_variant_as_bool(&v_); }
    godot_vector3 as_vector3() const { return core->godot_variant_as_vector3(&v_); }
    godot_transform as_transform() const { return core->godot_variant_as_transform(&v_); }
    std::string as_string() const;

  private:
    godot_variant v_;
};

/// Calls `cls.method` on `self` with Variant arguments (Godot's varcall); a nil Var when it fails.
Var call(godot_object* self, const char* cls, const char* method,
         std::initializer_list<const Var*> args = {});
/// Object::is_class: `self` is a `cls` or derives from it.
bool is_class(godot_object* self, const char* cls);
/// Object::get_instance_id: a stable key for an object while it lives.
std::uint64_t instance_id(godot_object* self);
/// A new instance of a Godot class (a Reference is owned by the returned Var).
Var make(const char* cls);

/// Elements of an Array variant.
std::vector<Var> array_items(const Var& array);

/// x, y, z of a Vector3.
struct Float3 {
    float x, y, z;
};
Float3 to_float3(const godot_vector3& v);
godot_vector3 to_vector3(float x, float y, float z);
/// A Transform as a column-major 4x4 (gust::Mat4's layout).
void to_column_major(const godot_transform& t, float out[16]);

} // namespace gust::godot

namespace gust::godot {

using SetFn = void (*)(godot_object*, void*, void*, godot_variant*);
using GetFn = godot_variant (*)(godot_object*, void*, void*);
using MethodFn = godot_variant (*)(godot_object*, void*, void*, int, godot_variant**);

/// NativeScript registration of a method and of an editor-visible, stored property.
void register_method(void* handle, const char* cls, const char* name, MethodFn fn);
void register_property(void* handle, const char* cls, const char* path, const Var& default_value,
                       godot_property_hint hint, const char* hint_string, SetFn set, GetFn get);
/// The NativeScript instance behind `object` when its script's type tag is `tag`, else null.
void* userdata_if(godot_object* object, const void* tag);

} // namespace gust::godot
