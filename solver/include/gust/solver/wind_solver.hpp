// The wind: Stam's stable fluids on a MAC grid around a focus point, with the sparse voxel tree as
// its solid boundary (docs/design.md "Wind solver", docs/solver.md).
#pragma once

#include <algorithm>
#include <cstdint>
#include <glm/glm.hpp>
#include <gust/gpu/buffer.hpp>
#include <gust/gpu/host_memory.hpp>
#include <gust/gpu/pipeline.hpp>
#include <gust/gpu/profiler.hpp>
#include <gust/voxelizer/sparse_tree.hpp>
#include <gust/voxelizer/voxel_world.hpp>
#include <memory>
#include <memory_resource>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace gust {

/// How velocities are carried by the flow.
enum class Advection {
    None,           ///< skipped (tests, pure projection)
    SemiLagrangian, ///< Stam 1999, midpoint backtrace
    MacCormack      ///< second order, clamped to the interpolated values (Selle et al. 2008)
};

/// How a step's work is laid out in passes (docs/solver.md, "Stages on a GPU and on a CPU device"). A GPU
/// pays for each stage (a dispatch after a barrier) with a drain; a CPU device pays for every instruction a
/// pass carries, and for a barrier inside a large pass, so work that rides along in a neighbouring pass to
/// save a stage costs it more than the stage.
enum class PassLayout {
    Auto,        ///< FewerStages on a GPU, LessWork on a CPU device (resolved at creation)
    FewerStages, ///< the warm start's scale summed in the advection's correction: one stage fewer a step
    LessWork     ///< the warm start's scale in a pass of its own
};

/// How the pressure equation is solved.
enum class PressureSolver {
    MultigridPCG, ///< conjugate gradients preconditioned by one V-cycle each (McAdams et al. 2010)
    Multigrid,    ///< geometric V-cycles alone, red-black Gauss–Seidel smoothing
    Jacobi        ///< the baseline
};

/// The smallest voxel (cell_size / voxels_per_cell) and the largest cell, metres: wind has no use beyond,
/// single precision places nothing beyond (cells of 1e-30 m made every solve diverge; 1e30 m overflows),
/// and OpenVDB's transforms (gust simulate's frames) hold no voxel below about 1.45e-5 m.
inline constexpr float kMinVoxelSize = 1e-4f;
inline constexpr float kMaxCellSize = 1000.0f;
/// The longest step a solver takes, seconds.
inline constexpr float kMaxStep = 10.0f;
/// The fastest ambient wind a solver takes, m/s.
inline constexpr float kMaxAmbientSpeed = 1e4f;
/// The most cascades a nest holds (WindSolver::couple).
inline constexpr std::uint32_t kMaxCascades = 8;
/// Cells over which a cascade's answer blends into the next coarser one's, inward from its border, where
/// the coarser cascade is open; where its cells around a point (trilinear on their open fractions) hold
/// kCascadeSolidShare of solid or more, over 1 cell (cascade_blend_cells).
inline constexpr float kCascadeBlendCells = 3.0f;
inline constexpr float kCascadeSolidShare = 0.3f;

/// The blend's width in cells where the next coarser cascade's open fraction (trilinear on its cells) is
/// `coarser_open`: a coarser grid resolves the solid it cuts coarsely, so near it the finer answers alone
/// to within a cell of its border (docs/solver.md "Cascades").
inline float cascade_blend_cells(float coarser_open) {
    const float open =
        std::clamp((coarser_open - (1.0f - kCascadeSolidShare)) / kCascadeSolidShare, 0.0f, 1.0f);
    return 1.0f + (kCascadeBlendCells - 1.0f) * open;
}
/// The most emitters a solver takes.
inline constexpr std::size_t kMaxEmitterCount = 64;
/// An emitter's largest |strength|, m/s, and largest falloff exponent.
inline constexpr float kMaxEmitterStrength = 1e4f;
inline constexpr float kMaxEmitterFalloff = 64.0f;

/// Wind-source profiles (see emitter_velocity in shaders/solver/solver_math.h).
enum class EmitterType { Directional, Omni, Vortex, CapsuleMotor, ConeMotor };

/// What WindSolver::sample answers at a point.
enum class PointSample {
    /// The solver's own field: inside a solid the solid's velocity, in the air trilinear on the faces plus
    /// the omni emitters' wind, beyond the grid the coarser cascades' faces or the ambient wind.
    Field,
    /// The wind as engines read it (the System's query, its texture and its snapshot): this cascade's
    /// texels (bind_texels) and each coarser one's, trilinear on their cell centres and blended as
    /// gust_wind.glsl blends them, beyond the coarsest the ambient wind. A cascade without bound texels is
    /// passed over.
    Wind,
};

/// A wind source. The air within reach is sped up along the emitter's flow towards `strength` with a
/// response time (SolverDesc::emitter_response); air already faster that way is left alone.
struct Emitter {
    EmitterType type = EmitterType::Omni;
    glm::vec3 position{0.0f};     ///< metres, world: centre, or a motor's start
    glm::vec3 direction{1, 0, 0}; ///< unit: flow (directional, motors) or axis (vortex)
    float radius = 1.0f;          ///< metres, > 0
    float strength = 0.0f;        ///< m/s at the centre, within ±kMaxEmitterStrength (negative reverses)
    float falloff = 1.0f;         ///< exponent p of (1 − d/radius)^p, 0..kMaxEmitterFalloff (0: uniform)
    float length = 0.0f;          ///< motors: metres along `direction`, >= 0
};

/// Grid and numerics of a solver.
struct SolverDesc {
    glm::uvec3 cells{32, 16, 32};      ///< wind cells per axis, each 8..256
    float cell_size = 1.0f;            ///< metres, > 0
    glm::vec3 origin{0.0f};            ///< world position of the grid's min corner, metres
    std::uint32_t voxels_per_cell = 4; ///< tree voxels per cell per axis, 1..8
    /// MacCormack by default: docs/solver.md ("Advection default") says why.
    Advection advection = Advection::MacCormack;
    PressureSolver pressure = PressureSolver::MultigridPCG;
    /// The solve stops when max |residual| <= tolerance · max |divergence before projection|.
    float tolerance = 1e-5f;
    /// V-cycles (conjugate-gradient iterations) per step at most; docs/solver.md says why 32.
    std::uint32_t max_cycles = 32;
    /// 0: solve to the tolerance, recording what the last step suggests (tools, tests); N > 0: record N
    /// V-cycles a step, at most max_cycles, the warm start carrying the rest to the next (a game's frame
    /// budget). Either way a step stops early once the tolerance is met.
    std::uint32_t cycles_per_step = 0;
    std::uint32_t max_iterations = 4000; ///< Jacobi iterations per step at most
    std::uint32_t smoothing = 2;         ///< Gauss–Seidel sweeps before and after each coarse correction
    float vorticity = 0.2f;              ///< confinement strength ε (0: off)
    float viscosity = 0.0f;              ///< kinematic viscosity, m^2/s (0: off)
    float emitter_response = 0.1f;       ///< seconds for an emitter to close 63% of the gap, > 0
    /// m/s, in (0, 256]: a moving surface pushes the air at most this fast (docs/solver.md "Motion").
    float max_solid_speed = 50.0f;
    /// Start each pressure solve from the last step's pressure, scaled to fit (docs/solver.md); false:
    /// from zero every step.
    bool warm_start = true;
    /// Auto is resolved at creation: desc() reports the layout the device got.
    PassLayout layout = PassLayout::Auto;
    /// The solver will have a neighbouring cascade (couple): its advection is built for the nest at
    /// creation, so that couple need not build it again. couple rebuilds it when the nesting differs.
    bool nested = false;
};

/// Where the solid boundary comes from: a tree over a voxel grid of cell_size / voxels_per_cell
/// voxels, and the moving surfaces' fragments with their velocities (as the voxelizer leaves them).
struct SolidSource {
    const SparseTree* tree = nullptr;        ///< null: no solids
    glm::ivec3 voxel_offset{0};              ///< tree voxel at the wind grid's min corner
    VkDeviceAddress fragments = 0;           ///< packed voxel keys of moving surfaces (0: none)
    VkDeviceAddress fragment_count = 0;      ///< uint counter
    VkDeviceAddress fragment_velocities = 0; ///< uvec2 half-float velocity per fragment, m/s
    std::uint64_t fragment_capacity = 0;
    /// VoxelWorld::static_generation(). While it, the tree and voxel_offset stay the same, a step redoes
    /// only the cells whose voxels a moving surface reaches now or reached at the last step; any change
    /// redoes every cell.
    std::uint64_t static_generation = 0;
};

/// What one step did.
struct WindStats {
    /// `memory` holds the pass timings.
    explicit WindStats(std::pmr::memory_resource* memory = std::pmr::get_default_resource()) : ms(memory) {}
    double divergence_before = 0.0;    ///< max |divergence| before projection, 1/s
    double divergence_after = 0.0;     ///< the same after, 1/s
    double residual = 0.0;             ///< max |residual| at the last check, 1/s
    std::uint32_t cycles = 0;          ///< V-cycles (multigrid) or iterations (Jacobi) run
    std::uint32_t cycles_recorded = 0; ///< V-cycles or iterations the step recorded (docs/solver.md)
    bool converged = false;            ///< the tolerance was met
    std::uint32_t cut_cells = 0;       ///< cells holding solid voxels
    std::uint32_t fluid_cells = 0;     ///< cells with an open face
    std::uint32_t sealed_cells = 0;    ///< cells whose free voxels reach no open side (solid for the wind)
    /// The pressure solve diverged (docs/solver.md "Stability") and was stopped: nothing was projected.
    bool diverged = false;
    std::uint32_t moving_fragments = 0;
    gpu::Timings ms; ///< GPU milliseconds per pass (when timed)
};

/// The voxel grid of the tree that bounds a wind grid: min corner at the wind grid's, voxels
/// cell_size / voxels_per_cell wide, res the smallest power of `branching` (at least 8) spanning the
/// longest axis. Fails when that would pass the voxelizer's 1024 per axis.
Result<GridDesc> voxel_grid(const SolverDesc& desc, std::uint32_t branching);

/// The solid boundary a VoxelWorld over voxel_grid(desc) gives as of its last step: its tree and its
/// moving fragments. Take it again after every step (a step may reallocate the fragment list).
SolidSource solid_source(const VoxelWorld& world);

/// Fails on a grid or setting out of range (the message names it).
Status validate(const SolverDesc& desc);
/// Fails on non-finite or out-of-range emitter parameters (the message names emitter and field).
Status validate(std::span<const Emitter> emitters);

/// The solver. Thread-compatible; the Context must outlive it.
class WindSolver : public gpu::HostObject {
  public:
    /// Starts with the air at rest (see set_ambient).
    static Result<std::unique_ptr<WindSolver>> create(gpu::Context& ctx, const SolverDesc& desc);

    /// Ambient wind, m/s: enters through the domain's upwind faces, fills new cells when scrolling.
    /// Before the first step it also sets the air everywhere: a level loads into wind already blowing,
    /// rather than into still air that the first projection must set moving (a large, slow solve). After,
    /// the next step adds the change to the air everywhere before it advects (a new far field reaches
    /// incompressible air at once; its projection fits it to the solids), docs/solver.md "Ambient wind".
    Status set_ambient(glm::vec3 velocity);
    /// Nests this solver among cascades of one focus (docs/solver.md "Cascades"). From its next step, beyond
    /// its grid it takes the wind of `outer` (the next coarser cascade, and those beyond it) in place of the
    /// ambient wind: every side held at it but the one the ambient wind leaves through most, which stays open
    /// (shaderio::nested_open_sides); where `inner` (the next finer cascade) covers a face with at least
    /// one of this grid's cells inside inner's border, each step draws the face a quarter of the way
    /// (shaderio::kCascadeFeedback) from its own advected and forced value towards inner's wind averaged
    /// over it. Either may be null (null, null: one grid again). Each reads the other's
    /// field as its last step or scroll left it; `inner` reads this one's blended in time between its last
    /// two steps (record_keep_previous, record_time_blend). Both outlive the coupling. With an inner, it
    /// allocates a copy of the field (fails when it cannot).
    Status couple(const WindSolver* outer, const WindSolver* inner);
    /// Moves the grid, its field and its emitters by `offset` (world m, finite), for a world whose origin
    /// moved: the field keeps its values, now `offset` away. The next step redoes its solids.
    Status shift_origin(glm::vec3 offset);
    /// Replaces the emitters (at most 64). Rejected whole when any is invalid.
    Status set_emitters(std::span<const Emitter> emitters);
    /// Moves the grid by whole cells (origin += cells · cell_size): overlapping faces keep their
    /// values, the others take the ambient wind; the pressure moves alike (new cells 0). Blocks.
    Status scroll(glm::ivec3 cells);
    /// One step of dt seconds (finite, in (0, 10]): solid boundary, advection, emitters, vorticity
    /// confinement, viscosity, projection. Blocks until the GPU is done.
    Result<WindStats> step(float dt, const SolidSource* solid = nullptr);

    /// Face velocities (m/s) in the layout of shaders/solver/solver_io.h: x faces, then y, then z. Closed
    /// faces within two faces of the air hold the air's velocity extended into the solid (extend_face),
    /// deeper ones the solid's; read_solid_velocity() has what the solid imposes on closed faces.
    /// The field is replaced, so the next pressure solve starts from zero rather than warm.
    Status set_velocity(std::span<const float> faces);
    Result<std::vector<float>> read_velocity() const;
    /// Open fraction per face (1 open, 0 closed), as of the last step.
    Result<std::vector<float>> read_open_fraction() const;
    /// Solid's normal velocity per face (m/s), as of the last step.
    Result<std::vector<float>> read_solid_velocity() const;
    /// Pressure per cell, Pa (air density 1.2 kg/m^3), of the last step.
    Result<std::vector<float>> read_pressure() const;
    /// Fraction of each cell's voxels that are solid for the wind (occupied or sealed), of the last step:
    /// 1 inside closed meshes.
    Result<std::vector<float>> read_solid_fraction() const;
    /// Velocity (m/s, world) at each cell's centre, index x + X·(y + Y·z): the air's (the mean of its
    /// faces) where the cell has air, the solid's own where it has none. Blocks.
    Result<std::vector<glm::vec3>> read_cell_velocity();
    /// Every step from now on also writes its wind texture's texels into `texels` within its last pass,
    /// the same texels record_texels() writes for the field the step leaves: the one way a step writes
    /// texels. `texels` is checked by check_texels and outlives the solver (or the next bind_texels).
    void bind_texels(const gpu::Buffer& texels);
    /// V-cycles (Jacobi: blocks) the next step records.
    std::uint32_t cycles_per_step() const;

    /// Velocity (m/s, world) at each world point, read as `what` says (PointSample). Points must be finite.
    /// Blocks.
    Result<std::pmr::vector<glm::vec3>> sample(std::span<const glm::vec3> points,
                                               PointSample what = PointSample::Field);
    /// Writes each cell's texel into `texels` (8 bytes per cell, index x + X·(y + Y·z)): the velocity at
    /// the cell's centre (m/s) and 1 − its solid fraction, as four half floats; then records `then`
    /// into the same submission, after a barrier. Blocks. The texels bound by bind_texels stay bound:
    /// later steps write those, not `texels`.
    template <class Then> Status write_texels(const gpu::Buffer& texels, Then&& then) {
        if (Status s = check_texels(texels); !s) return s;
        return ctx_.submit_and_wait([&](VkCommandBuffer cmd) {
            record_texels(cmd, texels);
            then(cmd);
        });
    }

    // Frames in flight (gpu::Context::begin_frame): the same work recorded into the caller's command
    // buffer, which runs later. Each starts and ends with a barrier of its own.
    /// step() recorded; its stats come from record_readback() and stats_from() once the frame completed.
    Status record_step(VkCommandBuffer cmd, float dt, const SolidSource* solid = nullptr);
    /// Bytes record_readback() writes.
    static std::size_t readback_bytes();
    /// Records a copy of the recorded step's counters into `dst` at `offset`.
    void record_readback(VkCommandBuffer cmd, VkBuffer dst, VkDeviceSize offset) const;
    /// The stats of a recorded step from its readback (no pass timings); they also set how many
    /// V-cycles the steps recorded from now on hold (docs/solver.md, "Cycles recorded").
    WindStats stats_from(const void* readback);
    /// GPU milliseconds per pass of the step recorded while gpu::Context::begin_frame(`frame`) was
    /// current, once that frame completed; empty if none was recorded then.
    gpu::Timings timings(std::uint64_t frame) const;
    /// Records this solver's bindings as they stand (its origin, its field's buffer), for the cascades nested
    /// with it that read them before its next step does (after shift_origin).
    void record_bindings(VkCommandBuffer cmd);
    /// scroll() recorded (the origin moves now).
    void record_scroll(VkCommandBuffer cmd, glm::ivec3 cells);
    /// Cascades with an inner (couple): copies the field as it stands, and where it stands, for the finer
    /// cascade to blend from until the next keep. Recorded before the scroll and step it precedes.
    void record_keep_previous(VkCommandBuffer cmd);
    /// Adds the ambient wind's change since set_ambient last took effect to the field (and to the field kept
    /// by record_keep_previous) now, rather than at the next step; a cascade that does not step every frame
    /// takes a new far field in the frame it is set, with the rest of the nest. No-op without a change.
    void record_ambient_change(VkCommandBuffer cmd);
    /// Cascades with an inner: where the finer cascade's time now lies between the field kept by
    /// record_keep_previous (0) and the current one (1), clamped to [0, 1]; read by the finer cascade's
    /// passes recorded after it.
    void record_time_blend(VkCommandBuffer cmd, float blend);
    /// Fails when `texels` is too small for write_texels() or record_texels().
    Status check_texels(const gpu::Buffer& texels) const;
    /// write_texels() recorded, without `then` (`texels` checked by check_texels); a full-grid pass, for a
    /// texture's first fill (the steps write the bound texels themselves).
    void record_texels(VkCommandBuffer cmd, const gpu::Buffer& texels);
    /// sample() recorded: `count` vec3 points at device address `points` (finite), velocities to `samples`.
    void record_sample(VkCommandBuffer cmd, VkDeviceAddress points, VkDeviceAddress samples,
                       std::uint32_t count, PointSample what = PointSample::Field);

    const SolverDesc& desc() const { return desc_; }
    glm::vec3 origin() const { return origin_; }
    glm::vec3 ambient() const { return ambient_; }
    std::size_t face_count() const;
    std::size_t cell_count() const;
    std::uint32_t levels() const { return levels_; }

    ~WindSolver();

  private:
    explicit WindSolver(gpu::Context& ctx);
    void record_passes(VkCommandBuffer cmd, float dt, const SolidSource* solid);
    struct Impl;
    gpu::Context& ctx_;
    SolverDesc desc_;
    glm::vec3 origin_{0.0f};
    glm::vec3 ambient_{0.0f};
    glm::vec3 ambient_change_{0.0f}; ///< set_ambient's change since the last step, added at the next
    std::uint32_t levels_ = 1;
    float last_dt_ = 0.0f;
    std::uint32_t cycles_to_record_ = 0; ///< V-cycles the next step records (MGPCG and multigrid)
    std::unique_ptr<Impl> impl_;
};

} // namespace gust
