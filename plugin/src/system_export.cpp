// System::export_vdb and its C twin gust_system_export_vdb, apart from the rest of the plugin: they are the
// only code that needs OpenVDB, and engine bindings link gust_core, which leaves this file out, so the
// library an engine loads needs nothing beyond Vulkan's loader and the C/C++ runtime (docs/dependencies.md).
#include "gust_c_internal.hpp"
#include "system_impl.hpp"
#if GUST_WITH_OPENVDB
#include "vdb_writer.hpp"
#endif

namespace gust {

using namespace detail;

Outcome System::export_vdb(const char* path) {
    const WriterCall call(*impl_);
    if (!call) return WriterCall::busy("export_vdb");
    if (!path || !*path) return invalid("path is empty");
#if GUST_WITH_OPENVDB
    return guarded([&]() -> Outcome {
        Impl& m = *impl_;
        auto voxels = m.world->tree().leaf_voxels();
        if (!voxels) return device_failure(voxels.status());
        // Every cascade's wind, the finest first; what they read back lives until the file is written.
        struct Read {
            std::vector<glm::vec3> velocity;
            std::vector<float> solid, pressure;
        };
        std::vector<Read> read(m.coarse_solvers.size() + 1);
        std::vector<vdb::WindGrids> grids;
        for (std::size_t k = 0; k < read.size(); ++k) {
            WindSolver& solver = k == 0 ? *m.solver : *m.coarse_solvers[k - 1];
            auto velocity = solver.read_cell_velocity();
            auto solid = solver.read_solid_fraction();
            auto pressure = solver.read_pressure();
            for (const Status* s : {&velocity.status(), &solid.status(), &pressure.status()})
                if (!*s) return device_failure(*s);
            read[k] = {std::move(*velocity), std::move(*solid), std::move(*pressure)};
            grids.push_back({solver.desc().cells, solver.desc().cell_size, solver.origin(), read[k].solid,
                             read[k].velocity, read[k].pressure});
        }
        if (Status s = vdb::write_frame_vdb(path, *voxels, m.world->grid(), grids); !s)
            return Outcome(ErrorCode::IoError, s.message());
        return {};
    });
#else
    return Outcome(ErrorCode::Unsupported, std::string("cannot write ") + path +
                                               ": gust was built without OpenVDB (GUST_WITH_OPENVDB=OFF)");
#endif
}

} // namespace gust

extern "C" gust_result gust_system_export_vdb(gust_system system, const char* path) {
    using namespace gust::capi;
    return on_system(system, "gust_system_export_vdb", [&](gust::System& s) { return s.export_vdb(path); });
}
