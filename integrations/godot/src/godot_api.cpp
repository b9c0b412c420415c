#include "godot_api.hpp"

#include <cstring>
#include <map>
#include <mutex>
#include <utility>

namespace gust::godot {

const godot_gdnative_core_api_struct* core = nullptr;
const godot_gdnative_ext_nativescript_api_struct* nativescript = nullptr;
const godot_gdnative_ext_nativescript_1_1_api_struct* nativescript11 = nullptr;

void error(const std::string& message, const char* where) {
    core->godot_print_error(message.c_str(), where, "gust", 0);
}

void warning(const std::string& message, const char* where) {
    core->godot_print_warning(message.c_str(), where, "gust", 0);
}

Var::Var(const char* s) {
    godot_string str = core->godot_string_chars_to_utf8(s);
    core->godot_variant_new_string(&v_, &str);
    core->godot_string_destroy(&str);
}

Var& Var::operator=(const Var& o) {
    if (this != &o) {
        core->godot_variant_destroy(&v_);
        core->godot_variant_new_copy(&v_, &o.v_);
    }
    return *this;
}

godot_variant Var::release() {
    godot_variant out = v_;
    core->godot_variant_new_nil(&v_);
    return out;
}

godot_object* Var::object() const {
    return type() == GODOT_VARIANT_TYPE_OBJECT ? core->godot_variant_as_object(&v_) : nullptr;
}

std::string Var::as_string() const {
    godot_string s = core->godot_variant_as_string(&v_);
    godot_char_string utf8 = core->godot_string_utf8(&s);
    std::string out = core->godot_char_string_get_data(&utf8);
    core->godot_char_string_destroy(&utf8);
    core->godot_string_destroy(&s);
    return out;
}

namespace {

// Method binds are looked up once per (class, method) and live as long as Godot's ClassDB.
godot_method_bind* bind(const char* cls, const char* method) {
    static std::mutex mutex;
    static std::map<std::pair<std::string, std::string>, godot_method_bind*> binds;
    std::lock_guard lock(mutex);
    auto key = std::make_pair(std::string(cls), std::string(method));
    auto it = binds.find(key);
    if (it == binds.end()) {
        it = binds.emplace(key, core->godot_method_bind_get_method(cls, method)).first;
    }
    return it->second;
}

} // namespace

Var call(godot_object* self, const char* cls, const char* method, std::initializer_list<const Var*> args) {
    godot_method_bind* mb = bind(cls, method);
    if (mb == nullptr || self == nullptr) {
        error(std::string("no method ") + cls + "." + method, "gust");
        return Var();
    }
    const godot_variant* argv[8];
    int argc = 0;
    for (const Var* a : args) {
        argv[argc++] = a->get();
    }
    godot_variant_call_error err{};
    godot_variant result = core->godot_method_bind_call(mb, self, argv, argc, &err);
    if (err.error != GODOT_CALL_ERROR_CALL_OK) {
        core->godot_variant_destroy(&result);
        error(std::string("calling ") + cls + "." + method + " failed (call error " +
                  std::to_string(err.error) + ")",
              "gust");
        return Var();
    }
    return Var(result);
}

bool is_class(godot_object* self, const char* cls) {
    Var name(cls);
    return self != nullptr && call(self, "Object", "is_class", {&name}).as_bool();
}

std::uint64_t instance_id(godot_object* self) {
    return std::uint64_t(call(self, "Object", "get_instance_id").as_int());
}

Var make(const char* cls) {
    godot_class_constructor ctor = core->godot_get_class_constructor(cls);
    return ctor == nullptr ? Var() : Var(ctor());
}

std::vector<Var> array_items(const Var& array) {
    std::vector<Var> out;
    if (array.type() != GODOT_VARIANT_TYPE_ARRAY) {
        return out;
    }
    godot_array a = core->godot_variant_as_array(array.get());
    const godot_int n = core->godot_array_size(&a);
    out.reserve(std::size_t(n));
    for (godot_int i = 0; i < n; ++i) {
        out.emplace_back(core->godot_array_get(&a, i));
    }
    core->godot_array_destroy(&a);
    return out;
}

Float3 to_float3(const godot_vector3& v) {
    return {core->godot_vector3_get_axis(&v, GODOT_VECTOR3_AXIS_X),
            core->godot_vector3_get_axis(&v, GODOT_VECTOR3_AXIS_Y),
            core->godot_vector3_get_axis(&v, GODOT_VECTOR3_AXIS_Z)};
}

godot_vector3 to_vector3(float x, float y, float z) {
    godot_vector3 v;
    core->godot_vector3_new(&v, x, y, z);
    return v;
}

void to_column_major(const godot_transform& t, float out[16]) {
    // Godot 3's Transform is a Basis of three row vectors, then the origin (real_t is float).
    static_assert(sizeof(godot_transform) == 12 * sizeof(float));
    float f[12];
    std::memcpy(f, &t, sizeof(f));
    for (int col = 0; col < 3; ++col) {
        for (int row = 0; row < 3; ++row) {
            out[4 * col + row] = f[3 * row + col];
        }
        out[4 * col + 3] = 0.0f;
    }
    out[12] = f[9];
    out[13] = f[10];
    out[14] = f[11];
    out[15] = 1.0f;
}

} // namespace gust::godot

namespace gust::godot {

void register_method(void* handle, const char* cls, const char* name, MethodFn fn) {
    godot_instance_method m{};
    m.method = fn;
    godot_method_attributes attr{GODOT_METHOD_RPC_MODE_DISABLED};
    nativescript->godot_nativescript_register_method(handle, cls, name, attr, m);
}

void register_property(void* handle, const char* cls, const char* path, const Var& default_value,
                       godot_property_hint hint, const char* hint_string, SetFn set, GetFn get) {
    godot_property_attributes attr{};
    attr.rset_type = GODOT_METHOD_RPC_MODE_DISABLED;
    attr.type = default_value.type();
    attr.hint = hint;
    attr.hint_string = core->godot_string_chars_to_utf8(hint_string);
    attr.usage = GODOT_PROPERTY_USAGE_DEFAULT;
    core->godot_variant_new_copy(&attr.default_value, default_value.get());
    godot_property_set_func s{};
    s.set_func = set;
    godot_property_get_func g{};
    g.get_func = get;
    nativescript->godot_nativescript_register_property(handle, cls, path, &attr, s, g);
    core->godot_string_destroy(&attr.hint_string);
    core->godot_variant_destroy(&attr.default_value);
}

void* userdata_if(godot_object* object, const void* tag) {
    if (object == nullptr || nativescript11->godot_nativescript_get_type_tag(object) != tag) {
        return nullptr;
    }
    return nativescript->godot_nativescript_get_userdata(object);
}

} // namespace gust::godot
