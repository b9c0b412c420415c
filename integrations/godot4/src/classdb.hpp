// Registering the extension's classes, methods and properties with Godot's ClassDB. A method is one body over
// Variants already converted to its argument types; the Variant call (GDScript's dynamic calls) and the
// ptrcall (typed calls, validated calls) both reach it.
#pragma once

#include "godot.hpp"

#include <vector>

namespace gust::godot4 {

/// A method's argument or return value, or a property: its Godot type, and for objects the class name.
struct Slot {
    const char* name = "";
    GDExtensionVariantType type = GDEXTENSION_VARIANT_TYPE_NIL;
    const char* class_name = "";
};

struct ClassSpec;

/// The C++ side of an object of one of the extension's classes.
struct Instance {
    const ClassSpec* spec = nullptr;
    GDExtensionObjectPtr owner = nullptr; ///< the Godot object
    virtual ~Instance() = default;
};

/// The body of a method: `instance` is the object's C++ side, `args` the arguments in their declared types
/// (defaults filled in). It returns the result (nil for none).
using MethodBody = Variant (*)(Instance& instance, const Variant* args);

struct MethodSpec {
    const char* name = "";
    MethodBody body = nullptr;
    Slot result; ///< type NIL: returns nothing
    std::vector<Slot> args;
    std::vector<Variant> defaults; ///< for the last arguments
    bool is_const = false;
};

/// A class the extension adds to ClassDB, deriving from an engine class.
struct ClassSpec {
    const char* name = "";
    const char* parent = "";
    /// Makes the C++ side of a new object (deleted when Godot frees the object).
    Instance* (*create)() = nullptr;
    /// Godot's notifications (NOTIFICATION_ENTER_TREE...).
    void (*notification)(Instance& instance, std::int32_t what) = nullptr;
};

/// Registers the class; methods and properties follow.
void register_class(const ClassSpec& spec);
void register_method(const char* class_name, MethodSpec spec);
/// A property read and written through two methods already registered.
void register_property(const char* class_name, Slot property, const char* setter, const char* getter,
                       std::uint32_t hint = 0, const char* hint_string = "");
/// Unregisters every class, the last registered first.
void unregister_classes();

/// Godot's node notifications the nodes take.
inline constexpr std::int32_t kNotificationEnterTree = 10;
inline constexpr std::int32_t kNotificationExitTree = 11;
inline constexpr std::int32_t kNotificationPhysicsProcess = 16;
/// PROPERTY_HINT_ENUM
inline constexpr std::uint32_t kHintEnum = 2;

} // namespace gust::godot4
