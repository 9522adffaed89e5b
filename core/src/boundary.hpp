// What the core and pinrate must agree on, defined once here and exported by module.cpp:
// pinrate.compiled.boundary compares each with pinrate's own definition when it loads the
// core, and refuses a core that differs (pinrate.backend() then says which and why).
//
// Names cross the boundary, not positions: a kernel is asked for by its name, a measured
// block by its letter, each setting by its field name (module.cpp's Settings).
#pragma once

#include <array>
#include <stdexcept>
#include <string>

namespace pinrate_core {

// pinrate.solvers.singular.SINGULAR_RATIO: a square block is singular when
// |det M| <= SINGULAR_RATIO * prod_j ||M[:, j]||.
constexpr double kSingularRatio = 1e-10;
constexpr double kSingularRatioSquared = kSingularRatio * kSingularRatio;

// pinrate.checks.PHYSICAL_BOUND: the largest magnitude a checked q or twist entry may have.
constexpr double kPhysicalBound = 1e6;

// pinrate.kinematics.kinematic_model.UNIT_TOLERANCE: how far a continuous joint's (cos, sin)
// pair of a checked q may be off unit norm (pinocchio::isNormalized's precision).
constexpr double kUnitTolerance = 1e-6;

// pinrate.solvers.eigen.FLAT: Viete's branch takes a 3x3 whose shifted p >= -FLAT as a
// triple root.
constexpr double kFlat = 1e-200;

// The resolved-rate algorithms the core implements (pinrate.compiled.boundary.KERNELS): the
// enum is internal, the names cross.
enum Kernel { EXACT = 0, SCHUR = 1, MCA1 = 2, MCA2 = 3, MCA3 = 4, DLS = 5, KERNEL_COUNT = 6 };
constexpr std::array<const char *, KERNEL_COUNT> kKernelNames = {"exact", "schur", "mca1", "mca2", "mca3", "dls"};

inline Kernel kernel_of(const std::string &name) {
  for (int kernel = 0; kernel < KERNEL_COUNT; ++kernel)
    if (name == kKernelNames[kernel]) return static_cast<Kernel>(kernel);
  throw std::invalid_argument("the compiled core has no kernel " + name);
}

// What ended a run of the loop (pinrate.compiled.boundary.OUTCOMES, by value). INTERRUPTED
// never reaches Python: the binding raises the signal handler's exception instead.
enum Outcome { CONVERGED = 0, DIVERGING = 1, STALLED = 2, MAX_STEPS = 3, HANDBACK = 4, FULL = 5, INTERRUPTED = 6 };
constexpr std::array<const char *, INTERRUPTED> kOutcomeNames = {"CONVERGED", "DIVERGING", "STALLED",
                                                                 "MAX_STEPS", "HANDBACK",  "FULL"};

// Flags of a step taken here (pinrate.compiled.boundary.STEP_FLAGS: the pinrate.control.Status
// members met). A step the collision monitor halts carries COLLISION_HALTED alone, as
// Python's halt says no other condition.
enum StepFlag { SATURATED = 1, RATE_LIMITED_FLAG = 2, CLAMPED = 4, COLLISION_SLOWED_FLAG = 8, COLLISION_HALTED_FLAG = 16 };
struct NamedFlag {
  const char *name;
  int value;
};
constexpr std::array<NamedFlag, 5> kStepFlags = {{{"SATURATED", SATURATED},
                                                  {"RATE_LIMITED", RATE_LIMITED_FLAG},
                                                  {"CLAMPED", CLAMPED},
                                                  {"COLLISION_SLOWED", COLLISION_SLOWED_FLAG},
                                                  {"COLLISION_HALTED", COLLISION_HALTED_FLAG}}};

// The blocks the conditioning bound may measure (pinrate.compiled.boundary.MEASURABLE).
constexpr std::array<const char *, 3> kMeasurable = {"A", "W", "J"};

}  // namespace pinrate_core
