// The extension's entry point (gust.gdextension's entry_symbol): the interface is looked up, and the nodes
// are registered at the scene level.
#include "classdb.hpp"
#include "nodes.hpp"

namespace {

void initialize(void*, GDExtensionInitializationLevel level) {
    if (level == GDEXTENSION_INITIALIZATION_SCENE) {
        gust::godot4::bind_methods();
        gust::godot4::register_nodes();
    }
}

void deinitialize(void*, GDExtensionInitializationLevel level) {
    if (level == GDEXTENSION_INITIALIZATION_SCENE) {
        gust::godot4::release_godot_images();
        gust::godot4::unregister_classes();
    }
}

} // namespace

extern "C" __attribute__((visibility("default"))) GDExtensionBool
gust_godot4_init(GDExtensionInterfaceGetProcAddress get, GDExtensionClassLibraryPtr library,
                 GDExtensionInitialization* init) {
    if (!gust::godot4::load(get, library)) {
        return false;
    }
    init->initialize = initialize;
    init->deinitialize = deinitialize;
    init->userdata = nullptr;
    init->minimum_initialization_level = GDEXTENSION_INITIALIZATION_SCENE;
    return true;
}
