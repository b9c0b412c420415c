// Godot's entry points (the .gdnlib's symbol_prefix "godot_").
#include "godot_api.hpp"
#include "nodes.hpp"

#include <cstring>

extern "C" __attribute__((visibility("default"))) void
godot_gdnative_init(godot_gdnative_init_options* options) {
    using namespace gust::godot;
    core = options->api_struct;
    for (unsigned i = 0; i < core->num_extensions; ++i) {
        if (core->extensions[i]->type != GDNATIVE_EXT_NATIVESCRIPT) {
            continue;
        }
        nativescript =
            reinterpret_cast<const godot_gdnative_ext_nativescript_api_struct*>(core->extensions[i]);
        // NativeScript 1.1 (type tags, documentation) is chained behind 1.0.
        for (const godot_gdnative_api_struct* next = nativescript->next; next != nullptr; next = next->next) {
            if (next->version.major == 1 && next->version.minor == 1) {
                nativescript11 =
                    reinterpret_cast<const godot_gdnative_ext_nativescript_1_1_api_struct*>(next);
            }
        }
    }
}

extern "C" __attribute__((visibility("default"))) void
godot_gdnative_terminate(godot_gdnative_terminate_options*) {
    using namespace gust::godot;
    core = nullptr;
    nativescript = nullptr;
    nativescript11 = nullptr;
}

extern "C" __attribute__((visibility("default"))) void godot_nativescript_init(void* handle) {
    using namespace gust::godot;
    if (nativescript == nullptr || nativescript11 == nullptr) {
        core->godot_print_error("gust needs NativeScript 1.1 (Godot 3.1 or later)", "godot_nativescript_init",
                                "gust", 0);
        return;
    }
    register_gust_emitter(handle);
    register_gust_wind(handle);
}
