#pragma once
// Damped least-squares inverse kinematics of frame targets: the configuration change dq, on the
// velocity columns that may move, that minimizes
//   |J dq + e|² + μ |dq|²,   dq = -Jᵀ (J Jᵀ + μ I)⁻¹ e
// (Levenberg's damping, in the row space: the system is rows × rows, a few feet's 3 or 6 rows
// against a robot's tens of joints), with e the stacked errors of the targets (current ⊖ target)
// and J their Jacobians on those columns. μ keeps the step bounded where J loses rank (a straight
// knee, a target out of reach): the step then shrinks instead of growing without bound. μ is
// λ², the square of the damping length (e.g. 1e-4 for 1 cm).
//
// A target is a frame's position (3 rows) or its placement (6 rows), in the world:
//   position:  e = p_f − p*, J = the frame's LOCAL_WORLD_ALIGNED linear rows;
//   placement, ReferenceFrame::Local: e = log6(M*⁻¹ M_f), J = Jlog6(M*⁻¹ M_f) J_local, the exact
//     derivative of that error (Gauss-Newton on the SE(3) log: quadratic convergence near the
//     solution);
//   placement, ReferenceFrame::LocalWorldAligned: e = [p_f − p*; log3(R_f R*ᵀ)] in world axes,
//     J = the frame's LOCAL_WORLD_ALIGNED rows (first order: the position error does not mix with
//     the rotation's, which is what a step that tracks a moving target wants).
//
// The workspace is allocated at construction; step and solve allocate nothing (a caller may run
// them every millisecond). Frames, dimensions and columns are checked at construction
// (std::invalid_argument).

#include <Eigen/Cholesky>
#include <limits>
#include <vector>

#include "solver/multibody/data.hpp"
#include "solver/multibody/model.hpp"

namespace stride {

struct IkTarget {
  int frame = -1;
  int dim = 3;  // 3: position, 6: placement
  // For a placement: how its error is taken (Local or LocalWorldAligned, above).
  ReferenceFrame error = ReferenceFrame::Local;
  SE3 placement;  // world; a position target reads its translation only
};

struct InverseKinematicsOptions {
  // μ = λ² [m², rad²], added to the diagonal of J Jᵀ: the step minimizes |J dq + e|² + μ |dq|².
  double damping = 1e-8;
  int max_iterations = 100;
  double tolerance = 1e-10;  // solve() stops when |e| is below it
  // The largest error one step corrects: a larger e is scaled down to this norm first (a step
  // towards a far target, not an extrapolation of the linear model).
  double max_error = std::numeric_limits<double>::infinity();
};

enum class IkStatus {
  Converged,      // |e| < tolerance
  MaxIterations,  // not within tolerance after max_iterations (out of reach, or too few)
  NotFinite,      // a non-finite configuration or error
};
const char* toString(IkStatus status);

struct IkResult {
  IkStatus status = IkStatus::MaxIterations;
  int iterations = 0;  // steps taken
  double error = 0.0;  // |e| at the returned configuration
  bool converged() const { return status == IkStatus::Converged; }
};

class InverseKinematics {
 public:
  // columns: the velocity indices the IK may move (each once, within nv), e.g. jointColumns.
  InverseKinematics(const Model& model, std::vector<IkTarget> targets, std::vector<int> columns,
                    const InverseKinematicsOptions& options = {});
  // Every velocity index but a free-flyer's: the joints move, the base stays.
  static std::vector<int> jointColumns(const Model& model);

  const Model& model() const { return model_; }
  const InverseKinematicsOptions& options() const { return options_; }
  void setOptions(const InverseKinematicsOptions& options) { options_ = options; }
  int targets() const { return static_cast<int>(targets_.size()); }
  const IkTarget& target(int i) const { return targets_[i]; }
  void setTarget(int i, const SE3& placement) { targets_[i].placement = placement; }
  const std::vector<int>& columns() const { return columns_; }
  int rows() const { return rows_; }

  // Iterates q ← q ⊕ dq from q (in place, size nq) until |e| < tolerance or max_iterations
  // steps; q is the last iterate either way. Kinematics in its own workspace.
  IkResult solve(Eigen::Ref<Eigen::VectorXd> q);
  // One step at the kinematics `data` holds (computeJointJacobians at the configuration; the
  // targets' frame placements are updated here): dv (size nv) is dq on the columns, zero elsewhere.
  // Returns |e| (before max_error's scaling).
  double stepFromKinematics(Data& data, Eigen::Ref<Eigen::VectorXd> dv);
  // The errors and their Jacobian on the columns (rows × columns) of the last step.
  const Eigen::VectorXd& error() const { return e_; }
  const Eigen::MatrixXd& jacobian() const { return J_; }

 private:
  // e_ and J_ at the kinematics of data.
  void evaluate(Data& data);
  // dv from e_ and J_.
  void dampedStep(Eigen::Ref<Eigen::VectorXd> dv);

  const Model& model_;
  std::vector<IkTarget> targets_;
  std::vector<int> columns_;
  InverseKinematicsOptions options_;
  int rows_ = 0;
  Data data_;
  Matrix6Xd J_frame_;  // 6 × nv, one target's frame Jacobian
  // 6 × columns, its selected columns (dynamic rows: the product with Jlog6 then takes the same
  // kernel as for a block of a dynamic matrix, so a hand-written loop it replaces gives the same
  // bits).
  Eigen::MatrixXd J6_;
  Eigen::MatrixXd J_, JJt_;  // rows × columns, rows × rows
  Eigen::VectorXd e_, y_, dq_, dv_, q_next_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
};

}  // namespace stride
