#include "godot.hpp"

namespace gust::godot4 {

Interface gd;
Methods methods;

namespace {

template <class F> bool find(GDExtensionInterfaceGetProcAddress get, const char* name, F& out) {
    out = reinterpret_cast<F>(get(name));
    return out != nullptr;
}

// A builtin method of a builtin type, looked up once.
GDExtensionPtrBuiltInMethod builtin(GDExtensionVariantType type, const char* name, std::int64_t hash) {
    const StringName method(name);
    return gd.builtin_method(type, method.ptr(), hash);
}

std::int64_t packed_size(GDExtensionVariantType type, std::int64_t hash, const void* self) {
    std::int64_t n = 0;
    // "size" is a const method: Godot reads the base, never writes it.
    builtin(type, "size", hash)(const_cast<void*>(self), nullptr, &n, 0);
    return n;
}

void packed_resize(GDExtensionVariantType type, std::int64_t hash, void* self, std::int64_t n) {
    std::int64_t error = 0;
    const GDExtensionConstTypePtr args[1] = {&n};
    builtin(type, "resize", hash)(self, args, &error, 1);
}

} // namespace

bool load(GDExtensionInterfaceGetProcAddress get, GDExtensionClassLibraryPtr library) {
    gd.library = library;
    return find(get, "print_error_with_message", gd.print_error) &&
           find(get, "print_warning_with_message", gd.print_warning) &&
           find(get, "variant_new_nil", gd.variant_new_nil) &&
           find(get, "variant_new_copy", gd.variant_new_copy) &&
           find(get, "variant_destroy", gd.variant_destroy) &&
           find(get, "variant_get_type", gd.variant_get_type) &&
           find(get, "variant_booleanize", gd.variant_booleanize) &&
           find(get, "variant_construct", gd.variant_construct) &&
           find(get, "get_variant_from_type_constructor", gd.from_type) &&
           find(get, "get_variant_to_type_constructor", gd.to_type) &&
           find(get, "variant_get_ptr_constructor", gd.constructor) &&
           find(get, "variant_get_ptr_destructor", gd.destructor) &&
           find(get, "variant_get_ptr_builtin_method", gd.builtin_method) &&
           find(get, "string_name_new_with_latin1_chars", gd.string_name_new) &&
           find(get, "string_new_with_utf8_chars", gd.string_new) &&
           find(get, "array_operator_index", gd.array_index) &&
           find(get, "packed_vector3_array_operator_index", gd.vector3_array_index) &&
           find(get, "packed_vector3_array_operator_index_const", gd.vector3_array_index_const) &&
           find(get, "dictionary_operator_index", gd.dictionary_index) &&
           find(get, "packed_int32_array_operator_index", gd.int32_array_index) &&
           find(get, "packed_float32_array_operator_index", gd.float32_array_index) &&
           find(get, "packed_byte_array_operator_index", gd.byte_array_index) &&
           find(get, "object_method_bind_call", gd.method_bind_call) &&
           find(get, "object_method_bind_ptrcall", gd.method_bind_ptrcall) &&
           find(get, "object_set_instance", gd.object_set_instance) &&
           find(get, "object_cast_to", gd.object_cast_to) &&
           find(get, "object_get_instance_id", gd.object_get_instance_id) &&
           find(get, "global_get_singleton", gd.global_get_singleton) &&
           find(get, "classdb_construct_object2", gd.construct_object) &&
           find(get, "classdb_get_method_bind", gd.get_method_bind) &&
           find(get, "classdb_get_class_tag", gd.get_class_tag) &&
           find(get, "classdb_register_extension_class5", gd.register_class) &&
           find(get, "classdb_register_extension_class_method", gd.register_method) &&
           find(get, "classdb_register_extension_class_property", gd.register_property) &&
           find(get, "classdb_unregister_extension_class", gd.unregister_class);
}

void error(const std::string& message, const char* function, const char* file, int line) {
    gd.print_error(message.c_str(), message.c_str(), function, file, line, false);
}

void warning(const std::string& message, const char* function, const char* file, int line) {
    gd.print_warning(message.c_str(), message.c_str(), function, file, line, false);
}

StringName::StringName(const char* text) {
    gd.string_name_new(data_, text, false);
}

String::String(const char* text) {
    gd.string_new(data_, text);
}

std::int64_t Array::size() const {
    return packed_size(GDEXTENSION_VARIANT_TYPE_ARRAY, hash::Array_size, data_);
}

void Array::append(const Variant& item) {
    const GDExtensionConstTypePtr args[1] = {item.ptr()};
    builtin(GDEXTENSION_VARIANT_TYPE_ARRAY, "append", hash::Array_append)(data_, args, nullptr, 1);
}

void Dictionary::set(const char* key, const Variant& value) {
    const String text(key);
    const Variant k = Variant::from(GDEXTENSION_VARIANT_TYPE_STRING, text.ptr());
    GDExtensionVariantPtr slot = gd.dictionary_index(data_, k.ptr());
    gd.variant_destroy(slot);
    gd.variant_new_copy(slot, value.ptr());
}

std::int64_t PackedVector3Array::size() const {
    return packed_size(GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY, hash::PackedVector3Array_size, data_);
}

void PackedVector3Array::resize(std::int64_t n) {
    packed_resize(GDEXTENSION_VARIANT_TYPE_PACKED_VECTOR3_ARRAY, hash::PackedVector3Array_resize, data_, n);
}

Vec3* PackedVector3Array::data() {
    static_assert(sizeof(Vec3) == 12, "Godot's Vector3 is three floats");
    return size() ? static_cast<Vec3*>(gd.vector3_array_index(data_, 0)) : nullptr;
}

const Vec3* PackedVector3Array::data() const {
    return size() ? static_cast<const Vec3*>(gd.vector3_array_index_const(data_, 0)) : nullptr;
}

std::int64_t PackedFloat32Array::size() const {
    return packed_size(GDEXTENSION_VARIANT_TYPE_PACKED_FLOAT32_ARRAY, hash::PackedFloat32Array_size, data_);
}

std::int64_t PackedInt32Array::size() const {
    return packed_size(GDEXTENSION_VARIANT_TYPE_PACKED_INT32_ARRAY, hash::PackedInt32Array_size, data_);
}

void PackedByteArray::resize(std::int64_t n) {
    packed_resize(GDEXTENSION_VARIANT_TYPE_PACKED_BYTE_ARRAY, hash::PackedByteArray_resize, data_, n);
}

Mat4 to_mat4(const Transform3D& t) {
    Mat4 m;
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
            m.m[4 * c + r] = t.rows[r][c];
        }
        m.m[4 * c + 3] = 0.0f;
        m.m[12 + c] = t.origin[c];
    }
    m.m[15] = 1.0f;
    return m;
}

Variant& Variant::operator=(const Variant& other) {
    if (this != &other) {
        gd.variant_destroy(data_);
        gd.variant_new_copy(data_, other.data_);
    }
    return *this;
}

Variant Variant::from(GDExtensionVariantType type, const void* value) {
    Variant v;
    // The constructor reads `value` only; nil holds nothing, so writing over it leaks nothing.
    gd.from_type(type)(v.data_, const_cast<void*>(value));
    return v;
}

Variant Variant::from(bool v) {
    const GDExtensionBool b = v;
    return from(GDEXTENSION_VARIANT_TYPE_BOOL, &b);
}

Variant Variant::from(std::int64_t v) {
    return from(GDEXTENSION_VARIANT_TYPE_INT, &v);
}

Variant Variant::from(double v) {
    return from(GDEXTENSION_VARIANT_TYPE_FLOAT, &v);
}

Variant Variant::from(const Vec3& v) {
    return from(GDEXTENSION_VARIANT_TYPE_VECTOR3, &v);
}

Variant Variant::from(const StringName& v) {
    return from(GDEXTENSION_VARIANT_TYPE_STRING_NAME, v.ptr());
}

Variant Variant::from(GDExtensionObjectPtr v) {
    return from(GDEXTENSION_VARIANT_TYPE_OBJECT, &v);
}

void Variant::to(GDExtensionVariantType type, void* out) const {
    gd.to_type(type)(out, const_cast<unsigned char*>(data_));
}

GDExtensionObjectPtr Variant::object() const {
    GDExtensionObjectPtr o = nullptr;
    if (type() == GDEXTENSION_VARIANT_TYPE_OBJECT) {
        to(GDEXTENSION_VARIANT_TYPE_OBJECT, &o);
    }
    return o;
}

std::int64_t Variant::as_int() const {
    std::int64_t n = 0;
    if (type() == GDEXTENSION_VARIANT_TYPE_INT) {
        to(GDEXTENSION_VARIANT_TYPE_INT, &n);
    }
    return n;
}

Method::Method(const char* class_name, const char* method, std::int64_t hash) : name_(method) {
    const StringName c(class_name), m(method);
    bind_ = gd.get_method_bind(c.ptr(), m.ptr(), hash);
    if (!bind_) {
        GUST_GODOT_ERROR(std::string("Godot has no method ") + class_name + "." + method + " with the hash " +
                         std::to_string(hash) + " of the API the extension was built against");
    }
}

Variant Method::operator()(GDExtensionObjectPtr self, std::initializer_list<Variant> args) const {
    Variant result;
    if (!bind_) {
        return result;
    }
    // Room for the longest engine method bound (texture_create_from_extension takes 10): 8, as before,
    // overran the array and handed Godot a null argument.
    GDExtensionConstVariantPtr pointers[kMaxArguments] = {};
    if (args.size() > kMaxArguments) {
        GUST_GODOT_ERROR(std::string("calling ") + name_ + " with " + std::to_string(args.size()) +
                         " arguments: the extension passes at most " + std::to_string(kMaxArguments));
        return result;
    }
    std::size_t n = 0;
    for (const Variant& a : args) {
        pointers[n++] = a.ptr();
    }
    GDExtensionCallError call{};
    gd.method_bind_call(bind_, self, pointers, GDExtensionInt(n), result.ptr(), &call);
    if (call.error != GDEXTENSION_CALL_OK) {
        GUST_GODOT_ERROR(std::string("calling ") + name_ + " failed (GDExtensionCallErrorType " +
                         std::to_string(int(call.error)) + ", argument " + std::to_string(call.argument) +
                         ")");
    }
    return result;
}

void bind_methods() {
    methods.set_physics_process = {"Node", "set_physics_process", hash::Node_set_physics_process};
    methods.get_children = {"Node", "get_children", hash::Node_get_children};
    methods.get_tree = {"Node", "get_tree", hash::Node_get_tree};
    methods.get_physics_process_delta_time = {"Node", "get_physics_process_delta_time",
                                              hash::Node_get_physics_process_delta_time};
    methods.get_global_transform = {"Node3D", "get_global_transform", hash::Node3D_get_global_transform};
    methods.get_nodes_in_group = {"SceneTree", "get_nodes_in_group", hash::SceneTree_get_nodes_in_group};
    methods.get_mesh = {"MeshInstance3D", "get_mesh", hash::MeshInstance3D_get_mesh};
    methods.get_skin = {"MeshInstance3D", "get_skin", hash::MeshInstance3D_get_skin};
    methods.get_skeleton_path = {"MeshInstance3D", "get_skeleton_path",
                                 hash::MeshInstance3D_get_skeleton_path};
    methods.get_node_or_null = {"Node", "get_node_or_null", hash::Node_get_node_or_null};
    methods.surface_get_format = {"ArrayMesh", "surface_get_format", hash::ArrayMesh_surface_get_format};
    methods.get_bone_count = {"Skeleton3D", "get_bone_count", hash::Skeleton3D_get_bone_count};
    methods.get_bone_global_pose = {"Skeleton3D", "get_bone_global_pose",
                                    hash::Skeleton3D_get_bone_global_pose};
    methods.get_bone_rest = {"Skeleton3D", "get_bone_rest", hash::Skeleton3D_get_bone_rest};
    methods.get_bone_parent = {"Skeleton3D", "get_bone_parent", hash::Skeleton3D_get_bone_parent};
    methods.find_bone = {"Skeleton3D", "find_bone", hash::Skeleton3D_find_bone};
    methods.get_bind_count = {"Skin", "get_bind_count", hash::Skin_get_bind_count};
    methods.get_bind_name = {"Skin", "get_bind_name", hash::Skin_get_bind_name};
    methods.get_bind_bone = {"Skin", "get_bind_bone", hash::Skin_get_bind_bone};
    methods.get_bind_pose = {"Skin", "get_bind_pose", hash::Skin_get_bind_pose};
    methods.get_surface_count = {"Mesh", "get_surface_count", hash::Mesh_get_surface_count};
    methods.surface_get_arrays = {"Mesh", "surface_get_arrays", hash::Mesh_surface_get_arrays};
    methods.reference = {"RefCounted", "reference", hash::RefCounted_reference};
    methods.image_create_from_data = {"Image", "create_from_data", hash::Image_create_from_data};
    methods.texture3d_create = {"ImageTexture3D", "create", hash::ImageTexture3D_create};
    methods.texture3d_update = {"ImageTexture3D", "update", hash::ImageTexture3D_update};
    methods.global_shader_parameter_add = {"RenderingServer", "global_shader_parameter_add",
                                           hash::RenderingServer_global_shader_parameter_add};
    methods.global_shader_parameter_set = {"RenderingServer", "global_shader_parameter_set",
                                           hash::RenderingServer_global_shader_parameter_set};
    methods.get_rendering_device = {"RenderingServer", "get_rendering_device",
                                    hash::RenderingServer_get_rendering_device};
    methods.get_driver_resource = {"RenderingDevice", "get_driver_resource",
                                   hash::RenderingDevice_get_driver_resource};
    methods.texture_create_from_extension = {"RenderingDevice", "texture_create_from_extension",
                                             hash::RenderingDevice_texture_create_from_extension};
    methods.free_rid = {"RenderingDevice", "free_rid", hash::RenderingDevice_free_rid};
    methods.set_texture_rd_rid = {"Texture3DRD", "set_texture_rd_rid", hash::Texture3DRD_set_texture_rd_rid};
    methods.get_frames_drawn = {"Engine", "get_frames_drawn", hash::Engine_get_frames_drawn};
}

bool is_class(GDExtensionObjectPtr object, const char* class_name) {
    const StringName name(class_name);
    return object && gd.object_cast_to(object, gd.get_class_tag(name.ptr())) != nullptr;
}

} // namespace gust::godot4
