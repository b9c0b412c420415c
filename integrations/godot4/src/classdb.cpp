#include "classdb.hpp"

#include <deque>
#include <memory>

namespace gust::godot4 {

namespace {

// Everything Godot keeps a pointer to (method userdata, class userdata) lives here until the extension is
// unloaded; a deque never moves what it holds.
struct Registered {
    std::deque<ClassSpec> classes;
    std::deque<MethodSpec> methods;
};
Registered& registered() {
    static Registered r;
    return r;
}

// What a method's argument, result or a property looks like to Godot: its type and names, alive while the
// registration call runs.
struct Info {
    StringName name, class_name;
    String hint_string;
    GDExtensionPropertyInfo info{};
    Info(const Slot& slot, std::uint32_t hint = 0, const char* hint_text = "")
        : name(slot.name), class_name(slot.class_name), hint_string(hint_text) {
        info.type = slot.type;
        info.name = name.ptr();
        info.class_name = class_name.ptr();
        info.hint = hint;
        info.hint_string = hint_string.ptr();
        info.usage = 6; // PROPERTY_USAGE_DEFAULT: stored and shown in the editor
    }
};

void call(void* userdata, GDExtensionClassInstancePtr instance, const GDExtensionConstVariantPtr* args,
          GDExtensionInt count, GDExtensionVariantPtr result, GDExtensionCallError* error) {
    const MethodSpec& m = *static_cast<const MethodSpec*>(userdata);
    const std::size_t n = m.args.size();
    const std::size_t required = n - m.defaults.size();
    if (std::size_t(count) > n || std::size_t(count) < required) {
        error->error = std::size_t(count) > n ? GDEXTENSION_CALL_ERROR_TOO_MANY_ARGUMENTS
                                              : GDEXTENSION_CALL_ERROR_TOO_FEW_ARGUMENTS;
        error->expected = std::int32_t(std::size_t(count) > n ? n : required);
        return;
    }
    std::vector<Variant> converted(n);
    for (std::size_t i = 0; i < n; ++i) {
        if (i >= std::size_t(count)) {
            converted[i] = m.defaults[i - required];
            continue;
        }
        GDExtensionCallError construct{};
        // Godot's own conversion (an int where a float is declared...); refused conversions are the caller's.
        gd.variant_destroy(converted[i].ptr());
        gd.variant_construct(m.args[i].type, converted[i].ptr(), &args[i], 1, &construct);
        if (construct.error != GDEXTENSION_CALL_OK) {
            gd.variant_new_nil(converted[i].ptr());
            error->error = GDEXTENSION_CALL_ERROR_INVALID_ARGUMENT;
            error->argument = std::int32_t(i);
            error->expected = m.args[i].type;
            return;
        }
    }
    const Variant value = m.body(*static_cast<Instance*>(instance), converted.data());
    gd.variant_destroy(result);
    gd.variant_new_copy(result, value.ptr());
    error->error = GDEXTENSION_CALL_OK;
}

void ptrcall(void* userdata, GDExtensionClassInstancePtr instance, const GDExtensionConstTypePtr* args,
             GDExtensionTypePtr result) {
    const MethodSpec& m = *static_cast<const MethodSpec*>(userdata);
    std::vector<Variant> converted;
    converted.reserve(m.args.size());
    for (std::size_t i = 0; i < m.args.size(); ++i) {
        converted.push_back(Variant::from(m.args[i].type, args[i]));
    }
    const Variant value = m.body(*static_cast<Instance*>(instance), converted.data());
    if (m.result.type == GDEXTENSION_VARIANT_TYPE_NIL) {
        return;
    }
    if (m.result.type == GDEXTENSION_VARIANT_TYPE_OBJECT) {
        // A typed caller holds the returned object as a reference of its own (a Variant or a Ref it
        // initialized empty): take that reference for it, as Godot's own methods do.
        GDExtensionObjectPtr object = value.object();
        if (object && is_class(object, "RefCounted")) {
            methods.reference(object);
        }
        *static_cast<GDExtensionObjectPtr*>(result) = object;
        return;
    }
    value.to(m.result.type, result);
}

GDExtensionObjectPtr create_instance(void* userdata, GDExtensionBool) {
    const ClassSpec& c = *static_cast<const ClassSpec*>(userdata);
    const StringName parent(c.parent), name(c.name);
    GDExtensionObjectPtr owner = gd.construct_object(parent.ptr());
    Instance* instance = c.create();
    instance->spec = &c;
    instance->owner = owner;
    gd.object_set_instance(owner, name.ptr(), instance);
    return owner;
}

void free_instance(void*, GDExtensionClassInstancePtr instance) {
    delete static_cast<Instance*>(instance);
}

void notification(GDExtensionClassInstancePtr instance, std::int32_t what, GDExtensionBool) {
    Instance& self = *static_cast<Instance*>(instance);
    if (self.spec->notification) {
        self.spec->notification(self, what);
    }
}

GDExtensionClassCallVirtual no_virtual(void*, GDExtensionConstStringNamePtr, std::uint32_t) {
    return nullptr;
}

} // namespace

void register_class(const ClassSpec& spec) {
    ClassSpec& c = registered().classes.emplace_back(spec);
    GDExtensionClassCreationInfo5 info{};
    info.is_exposed = true;
    info.notification_func = notification;
    info.create_instance_func = create_instance;
    info.free_instance_func = free_instance;
    info.get_virtual_func = no_virtual;
    info.class_userdata = &c;
    const StringName name(c.name), parent(c.parent);
    gd.register_class(gd.library, name.ptr(), parent.ptr(), &info);
}

void register_method(const char* class_name, MethodSpec spec) {
    MethodSpec& m = registered().methods.emplace_back(std::move(spec));
    StringName cls(class_name), name(m.name);
    std::vector<std::unique_ptr<Info>> args;
    std::vector<GDExtensionPropertyInfo> arg_info;
    std::vector<GDExtensionClassMethodArgumentMetadata> metadata;
    for (const Slot& a : m.args) {
        args.push_back(std::make_unique<Info>(a));
        arg_info.push_back(args.back()->info);
        metadata.push_back(a.type == GDEXTENSION_VARIANT_TYPE_FLOAT
                               ? GDEXTENSION_METHOD_ARGUMENT_METADATA_REAL_IS_FLOAT
                               : GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE);
    }
    Info result(m.result);
    std::vector<GDExtensionVariantPtr> defaults;
    for (Variant& d : m.defaults) {
        defaults.push_back(d.ptr());
    }
    GDExtensionClassMethodInfo info{};
    info.name = name.ptr();
    info.method_userdata = &m;
    info.call_func = call;
    info.ptrcall_func = ptrcall;
    info.method_flags = GDEXTENSION_METHOD_FLAG_NORMAL | (m.is_const ? GDEXTENSION_METHOD_FLAG_CONST : 0);
    info.has_return_value = m.result.type != GDEXTENSION_VARIANT_TYPE_NIL;
    info.return_value_info = &result.info;
    info.return_value_metadata = m.result.type == GDEXTENSION_VARIANT_TYPE_FLOAT
                                     ? GDEXTENSION_METHOD_ARGUMENT_METADATA_REAL_IS_FLOAT
                                     : GDEXTENSION_METHOD_ARGUMENT_METADATA_NONE;
    info.argument_count = std::uint32_t(arg_info.size());
    info.arguments_info = arg_info.data();
    info.arguments_metadata = metadata.data();
    info.default_argument_count = std::uint32_t(defaults.size());
    info.default_arguments = defaults.data();
    gd.register_method(gd.library, cls.ptr(), &info);
}

void register_property(const char* class_name, Slot property, const char* setter, const char* getter,
                       std::uint32_t hint, const char* hint_string) {
    const StringName cls(class_name), set(setter), get(getter);
    Info info(property, hint, hint_string);
    gd.register_property(gd.library, cls.ptr(), &info.info, set.ptr(), get.ptr());
}

void unregister_classes() {
    auto& classes = registered().classes;
    for (auto it = classes.rbegin(); it != classes.rend(); ++it) {
        const StringName name(it->name);
        gd.unregister_class(gd.library, name.ptr());
    }
    classes.clear();
    registered().methods.clear();
}

} // namespace gust::godot4
