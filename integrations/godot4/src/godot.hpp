// The slice of Godot 4's GDExtension interface the extension uses, over the C header the engine dumps
// (godot --dump-gdextension-interface) and the method hashes gen_api.py reads from its API description: no
// godot-cpp, nothing of Godot's kept in the repository. Godot's types are held by their sizes in a
// single-precision build (gen_api.py refuses any other).
#pragma once

#include "godot4_api.gen.hpp"

#include <cstdint>
#include <gdextension_interface.h>
#include <gust/gust.hpp>
#include <initializer_list>
#include <span>
#include <string>
#include <utility>

namespace gust::godot4 {

/// The interface functions, looked up once by load().
struct Interface {
    GDExtensionClassLibraryPtr library = nullptr;
    GDExtensionInterfacePrintErrorWithMessage print_error = nullptr;
    GDExtensionInterfacePrintWarningWithMessage print_warning = nullptr;
    GDExtensionInterfaceVariantNewNil variant_new_nil = nullptr;
    GDExtensionInterfaceVariantNewCopy variant_new_copy = nullptr;
    GDExtensionInterfaceVariantDestroy variant_destroy = nullptr;
    GDExtensionInterfaceVariantGetType variant_get_type = nullptr;
    GDExtensionInterfaceVariantBooleanize variant_booleanize = nullptr;
    GDExtensionInterfaceVariantConstruct variant_construct = nullptr;
    GDExtensionInterfaceGetVariantFromTypeConstructor from_type = nullptr;
    GDExtensionInterfaceGetVariantToTypeConstructor to_type = nullptr;
    GDExtensionInterfaceVariantGetPtrConstructor constructor = nullptr;
    GDExtensionInterfaceVariantGetPtrDestructor destructor = nullptr;
    GDExtensionInterfaceVariantGetPtrBuiltinMethod builtin_method = nullptr;
    GDExtensionInterfaceStringNameNewWithLatin1Chars string_name_new = nullptr;
    GDExtensionInterfaceStringNewWithUtf8Chars string_new = nullptr;
    GDExtensionInterfaceArrayOperatorIndex array_index = nullptr;
    GDExtensionInterfacePackedVector3ArrayOperatorIndex vector3_array_index = nullptr;
    GDExtensionInterfacePackedVector3ArrayOperatorIndexConst vector3_array_index_const = nullptr;
    GDExtensionInterfaceDictionaryOperatorIndex dictionary_index = nullptr;
    GDExtensionInterfacePackedInt32ArrayOperatorIndex int32_array_index = nullptr;
    GDExtensionInterfacePackedFloat32ArrayOperatorIndex float32_array_index = nullptr;
    GDExtensionInterfacePackedByteArrayOperatorIndex byte_array_index = nullptr;
    GDExtensionInterfaceObjectMethodBindCall method_bind_call = nullptr;
    GDExtensionInterfaceObjectMethodBindPtrcall method_bind_ptrcall = nullptr;
    GDExtensionInterfaceObjectSetInstance object_set_instance = nullptr;
    GDExtensionInterfaceObjectCastTo object_cast_to = nullptr;
    GDExtensionInterfaceObjectGetInstanceId object_get_instance_id = nullptr;
    GDExtensionInterfaceGlobalGetSingleton global_get_singleton = nullptr;
    GDExtensionInterfaceClassdbConstructObject2 construct_object = nullptr;
    GDExtensionInterfaceClassdbGetMethodBind get_method_bind = nullptr;
    GDExtensionInterfaceClassdbGetClassTag get_class_tag = nullptr;
    GDExtensionInterfaceClassdbRegisterExtensionClass5 register_class = nullptr;
    GDExtensionInterfaceClassdbRegisterExtensionClassMethod register_method = nullptr;
    GDExtensionInterfaceClassdbRegisterExtensionClassProperty register_property = nullptr;
    GDExtensionInterfaceClassdbUnregisterExtensionClass unregister_class = nullptr;
};
/// Filled by load(); read-only afterwards.
extern Interface gd;
/// Looks every function up; false (nothing usable) when the engine lacks one.
bool load(GDExtensionInterfaceGetProcAddress get, GDExtensionClassLibraryPtr library);
/// Prints an error into Godot's log ("ERROR: message"), naming the C++ function and file.
void error(const std::string& message, const char* function, const char* file, int line);
#define GUST_GODOT_ERROR(message) ::gust::godot4::error((message), __func__, __FILE__, __LINE__)
/// Prints a warning into Godot's log ("WARNING: message").
void warning(const std::string& message, const char* function, const char* file, int line);
#define GUST_GODOT_WARNING(message) ::gust::godot4::warning((message), __func__, __FILE__, __LINE__)

class Variant;

/// A Godot builtin value held by its storage; made and destroyed by the engine's own functions for its type.
template <GDExtensionVariantType Type, std::size_t Size> class Builtin {
  public:
    Builtin() { gd.constructor(Type, 0)(data_, nullptr); }
    Builtin(const Builtin& other) {
        const GDExtensionConstTypePtr args[1] = {other.data_};
        gd.constructor(Type, 1)(data_, args);
    }
    Builtin& operator=(const Builtin& other) {
        if (this != &other) {
            gd.destructor(Type)(data_);
            const GDExtensionConstTypePtr args[1] = {other.data_};
            gd.constructor(Type, 1)(data_, args);
        }
        return *this;
    }
    ~Builtin() { gd.destructor(Type)(data_); }
    void* ptr() { return data_; }
    const void* ptr() const { return data_; }

  protected:
    alignas(8) unsigned char data_[Size];
};

class StringName : public Builtin<GDEXTENSION_VARIANT_TYPE_STRING_NAME, 8> {
  public:
    StringName() = default;
    explicit StringName(const char* text);
};
class String : public Builtin<GDEXTENSION_VARIANT_TYPE_STRING, 8> {
  public:
    String() = default;
    explicit String(const char* text);
};
/// Array: a list of Variants.
class Array : public Builtin<GDEXTENSION_VARIANT_TYPE_ARRAY, 8> {
  public:
    std::int64_t size() const;
    GDExtensionVariantPtr at(std::int64_t i) { return gd.array_index(data_, i); }
    void append(const Variant& item);
};
class Dictionary : public Builtin<GDEXTENSION_VARIANT_TYPE_DICTIONARY, 8> {
  public:
    void set(const char* key, const Variant& value);
};
class PackedVector3Array : public Builtin<GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY, 16> {
  public:
    std::int64_t size() const;
    void resize(std::int64_t n);
    /// The elements, x y z floats each (contiguous in Godot's storage); writing makes the array's own copy.
    Vec3* data();
    const Vec3* data() const;
};
class PackedInt32Array : public Builtin<GDEXTENSION_VARIANT_TYPE_PACKED_INT32_ARRAY, 16> {
  public:
    std::int64_t size() const;
    const std::int32_t* data() { return size() ? gd.int32_array_index(data_, 0) : nullptr; }
};
class PackedFloat32Array : public Builtin<GDEXTENSION_VARIANT_TYPE_PACKED_FLOAT32_ARRAY, 16> {
  public:
    std::int64_t size() const;
    const float* data() { return size() ? gd.float32_array_index(data_, 0) : nullptr; }
};
class PackedByteArray : public Builtin<GDEXTENSION_VARIANT_TYPE_PACKED_BYTE_ARRAY, 16> {
  public:
    void resize(std::int64_t n);
    std::uint8_t* data() { return gd.byte_array_index(data_, 0); }
};

/// Godot's Transform3D: a basis of three rows, then the origin.
struct Transform3D {
    float rows[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    float origin[3] = {0, 0, 0};
};
static_assert(sizeof(Transform3D) == 48);
/// The transform as gust's column-major 4x4.
Mat4 to_mat4(const Transform3D& t);

/// A Variant: any Godot value.
class Variant {
  public:
    Variant() { gd.variant_new_nil(data_); }
    Variant(const Variant& other) { gd.variant_new_copy(data_, other.data_); }
    Variant& operator=(const Variant& other);
    ~Variant() { gd.variant_destroy(data_); }
    /// Holds `value`, whose storage is of Godot type `type`.
    static Variant from(GDExtensionVariantType type, const void* value);
    static Variant from(bool v);
    static Variant from(std::int64_t v);
    static Variant from(double v);
    static Variant from(const Vec3& v);
    static Variant from(const StringName& v);
    static Variant from(GDExtensionObjectPtr v);
    /// Copies the value into `out`, whose storage is of Godot type `type` (initialized for types with a
    /// destructor): the Variant must hold that type.
    void to(GDExtensionVariantType type, void* out) const;
    GDExtensionVariantType type() const { return gd.variant_get_type(data_); }
    /// The object held, or null.
    GDExtensionObjectPtr object() const;
    std::int64_t as_int() const;
    GDExtensionVariantPtr ptr() { return data_; }
    GDExtensionConstVariantPtr ptr() const { return data_; }

  private:
    alignas(8) unsigned char data_[24];
};

/// A method of an engine class, bound once (at extension initialization) by its hash from the API dump.
class Method {
  public:
    Method() = default;
    Method(const char* class_name, const char* method, std::int64_t hash);
    /// The most arguments operator() passes.
    static constexpr std::size_t kMaxArguments = 16;
    /// Calls it on `self` (null for a static method) with at most kMaxArguments Variant arguments; errors go
    /// to Godot's log.
    Variant operator()(GDExtensionObjectPtr self, std::initializer_list<Variant> args = {}) const;
    bool valid() const { return bind_ != nullptr; }

  private:
    GDExtensionMethodBindPtr bind_ = nullptr;
    const char* name_ = "";
};

/// The engine methods the nodes call (godot.cpp binds them at the scene level's initialization).
struct Methods {
    Method set_physics_process, get_children, get_tree, get_global_transform, get_nodes_in_group, get_mesh,
        get_skin, get_skeleton_path, get_node_or_null, surface_get_format, get_bone_count,
        get_bone_global_pose, get_bone_rest, get_bone_parent, find_bone, get_bind_count, get_bind_name,
        get_bind_bone, get_bind_pose, get_physics_process_delta_time, get_surface_count, surface_get_arrays,
        reference, image_create_from_data, texture3d_create, texture3d_update, global_shader_parameter_add,
        global_shader_parameter_set, get_rendering_device, get_driver_resource, texture_create_from_extension,
        free_rid, set_texture_rd_rid, get_frames_drawn;
};
extern Methods methods;
void bind_methods();

/// True when `object` is an instance of engine class `class_name` (or derives from it).
bool is_class(GDExtensionObjectPtr object, const char* class_name);

} // namespace gust::godot4
