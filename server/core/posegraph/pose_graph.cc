#include "posegraph/pose_graph.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>

namespace objmap {
namespace {

// Error of one edge: the measured relative pose against the one the two node poses give,
// whitened by the square root of the information. Nodes: position (3) and unit quaternion (4,
// Eigen's x y z w order, on ceres::EigenQuaternionManifold).
class RelativePoseError {
 public:
  RelativePoseError(const Eigen::Isometry3d& T_from_to,
                    const Eigen::Matrix<double, 6, 6>& sqrt_info)
      : p_measured_(T_from_to.translation()),
        q_measured_(T_from_to.rotation()),
        sqrt_information_(sqrt_info) {}

  template <typename T>
  bool operator()(const T* p_from_ptr, const T* q_from_ptr, const T* p_to_ptr, const T* q_to_ptr,
                  T* residuals_ptr) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_from(p_from_ptr), p_to(p_to_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_from(q_from_ptr), q_to(q_to_ptr);
    const Eigen::Quaternion<T> q_from_inverse = q_from.conjugate();
    const Eigen::Quaternion<T> q_estimated = q_from_inverse * q_to;
    const Eigen::Matrix<T, 3, 1> p_estimated = q_from_inverse * (p_to - p_from);
    const Eigen::Quaternion<T> q_error = q_measured_.template cast<T>() * q_estimated.conjugate();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> residuals(residuals_ptr);
    residuals.template head<3>() = p_estimated - p_measured_.template cast<T>();
    residuals.template tail<3>() = T(2.0) * q_error.vec();
    residuals.applyOnTheLeft(sqrt_information_.template cast<T>());
    return true;
  }

  static ceres::CostFunction* Create(const Eigen::Isometry3d& T_from_to,
                                     const Eigen::Matrix<double, 6, 6>& sqrt_info) {
    return new ceres::AutoDiffCostFunction<RelativePoseError, 6, 3, 4, 3, 4>(
        new RelativePoseError(T_from_to, sqrt_info));
  }

 private:
  const Eigen::Vector3d p_measured_;
  const Eigen::Quaterniond q_measured_;
  const Eigen::Matrix<double, 6, 6> sqrt_information_;
};

}  // namespace

namespace {

// [a]x: the matrix of a x (.).
Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d skew;
  skew << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return skew;
}

}  // namespace

FixedDirections FixedDirectionsOf(const Eigen::Matrix<double, 6, 6>& H, double radius_m,
                                  double min_ratio) {
  FixedDirections fixed;
  fixed.scale.diagonal().tail<3>().setConstant(1.0 / std::max(radius_m, 1e-3));
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(fixed.scale * H *
                                                                          fixed.scale);
  const double largest = eigen.eigenvalues().maxCoeff();
  fixed.vectors = eigen.eigenvectors();
  for (int i = 0; i < 6; ++i) {
    const double value = eigen.eigenvalues()(i);
    fixed.values(i) = largest > 0.0 && value >= min_ratio * largest ? value : 0.0;
  }
  return fixed;
}

Eigen::Matrix<double, 6, 6> AlignmentInformation(const Eigen::Matrix<double, 6, 6>& H,
                                                 const Eigen::Vector3d& centre, double radius_m,
                                                 const Eigen::Vector3d& to_origin,
                                                 const AlignmentInformationConfig& config) {
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  const FixedDirections fixed = FixedDirectionsOf(H, radius_m, config.min_eigenvalue_ratio);
  const Matrix6d unscale = fixed.scale.inverse();
  const Matrix6d about_centre = unscale * fixed.vectors * fixed.values.asDiagonal() *
                                fixed.vectors.transpose() * unscale;
  // The pose graph turns about to's origin: dt_centre = dt + dtheta x (centre - to_origin), so
  // H = M^T H_centre M with M = [I, -[centre - to_origin]x; 0, I].
  Matrix6d M = Matrix6d::Identity();
  M.block<3, 3>(0, 3) = -Skew(centre - to_origin);
  Matrix6d geometric = M.transpose() * about_centre * M;
  geometric.diagonal().array() += 1.0;  // the weak prior: 1 m, 1 rad
  Matrix6d covariance = geometric.inverse();
  const double floor_rad = config.floor_sigma_deg * 0.017453292519943295;
  covariance.diagonal().head<3>().array() += config.floor_sigma_m * config.floor_sigma_m;
  covariance.diagonal().tail<3>().array() += floor_rad * floor_rad;
  const Matrix6d information = covariance.inverse();
  return 0.5 * (information + information.transpose());
}

bool PoseGraphConfig::IsValid(std::string* why) const {
  if (!(loop_loss_scale > 0.0) || !(loop_rejection_chi2 > 0.0) || max_iterations < 1 ||
      threads < 1) {
    *why =
        "pose graph: loop_loss_scale and loop_rejection_chi2 must be positive, max_iterations "
        "and threads >= 1";
    return false;
  }
  return true;
}

PoseGraph::PoseGraph(const PoseGraphConfig& config) : config_(config) {}

void PoseGraph::AddNode(int id, const Eigen::Isometry3d& T_W_N) {
  poses_[id] = T_W_N;
  if (!fixed_set_ && fixed_.empty()) fixed_.insert(id);
}

void PoseGraph::SetFixed(int id) {
  if (!fixed_set_) fixed_.clear();
  fixed_.insert(id);
  fixed_set_ = true;
}

bool PoseGraph::AddEdge(const PoseGraphEdge& edge, std::string* why) {
  if (poses_.count(edge.from) == 0 || poses_.count(edge.to) == 0) {
    *why = "edge " + std::to_string(edge.from) + " -> " + std::to_string(edge.to) +
           ": unknown node";
    return false;
  }
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(edge.information);
  if (!edge.information.allFinite() || !edge.information.isApprox(edge.information.transpose()) ||
      llt.info() != Eigen::Success) {
    *why = "edge " + std::to_string(edge.from) + " -> " + std::to_string(edge.to) +
           ": the information matrix is not symmetric positive definite";
    return false;
  }
  edges_.push_back(edge);
  return true;
}

namespace {

struct NodeState {
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

// The whitened residual of `edge` at the node states, without any loss.
double WhitenedSquaredError(const PoseGraphEdge& edge, const std::map<int, NodeState>& state) {
  const NodeState& from = state.at(edge.from);
  const NodeState& to = state.at(edge.to);
  const RelativePoseError error(edge.T_from_to, edge.information.llt().matrixU());
  Eigen::Matrix<double, 6, 1> residual;
  error(from.p.data(), from.q.coeffs().data(), to.p.data(), to.q.coeffs().data(),
        residual.data());
  return residual.squaredNorm();
}

// One Ceres solve from `poses` with the edges marked active; the optimum in `state`.
bool SolveGraph(const PoseGraphConfig& config_, const std::map<int, Eigen::Isometry3d>& poses_,
                const std::vector<PoseGraphEdge>& edges_, const std::set<int>& fixed_,
                const std::vector<bool>& active, std::map<int, NodeState>* state_out,
                PoseGraphReport* report, std::string* why) {
  std::map<int, NodeState>& state = *state_out;

  // Ceres works on plain arrays: a position and a quaternion per node.
  state.clear();
  for (const auto& [id, T] : poses_) {
    state[id] = {T.translation(), Eigen::Quaterniond(T.rotation())};
  }

  ceres::Problem problem;
  ceres::Manifold* quaternion_manifold = new ceres::EigenQuaternionManifold;
  for (std::size_t e = 0; e < edges_.size(); ++e) {
    if (!active[e]) continue;
    const PoseGraphEdge& edge = edges_[e];
    const Eigen::Matrix<double, 6, 6> sqrt_info = edge.information.llt().matrixU();
    ceres::LossFunction* loss =
        edge.loop ? new ceres::CauchyLoss(config_.loop_loss_scale) : nullptr;
    NodeState& from = state[edge.from];
    NodeState& to = state[edge.to];
    problem.AddResidualBlock(RelativePoseError::Create(edge.T_from_to, sqrt_info), loss,
                             from.p.data(), from.q.coeffs().data(), to.p.data(),
                             to.q.coeffs().data());
  }
  // Every node is in an edge (Optimize has edges, and AddEdge checks their nodes), except nodes
  // no edge names: those stay where they are. The problem owns the manifold once it uses it.
  bool manifold_used = false;
  for (auto& [id, node] : state) {
    if (!problem.HasParameterBlock(node.q.coeffs().data())) continue;
    problem.SetManifold(node.q.coeffs().data(), quaternion_manifold);
    manifold_used = true;
  }
  if (!manifold_used) delete quaternion_manifold;
  for (const int id : fixed_) {
    const auto fixed = state.find(id);
    if (fixed != state.end() && problem.HasParameterBlock(fixed->second.p.data())) {
      problem.SetParameterBlockConstant(fixed->second.p.data());
      problem.SetParameterBlockConstant(fixed->second.q.coeffs().data());
    }
  }

  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = config_.max_iterations;
  options.num_threads = config_.threads;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  const auto start = std::chrono::steady_clock::now();
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    *why = "Ceres: " + summary.message;
    return false;
  }
  report->converged = summary.termination_type == ceres::CONVERGENCE;
  report->iterations += static_cast<int>(summary.iterations.size());
  if (report->initial_cost == 0.0) report->initial_cost = summary.initial_cost;
  report->final_cost = summary.final_cost;
  report->solve_ms += std::chrono::duration<double, std::milli>(
                          std::chrono::steady_clock::now() - start)
                          .count();
  return true;
}

}  // namespace

bool PoseGraph::Optimize(PoseGraphReport* report, std::string* why) {
  if (!config_.IsValid(why)) return false;
  *report = PoseGraphReport{};
  if (poses_.size() < 2 || edges_.empty()) {
    *why = "the pose graph needs two nodes and an edge";
    return false;
  }
  std::vector<bool> active(edges_.size(), true);
  for (const PoseGraphEdge& edge : edges_) report->loops += edge.loop ? 1 : 0;
  // Solve; if a loop still disagrees with the optimum beyond the chi-square bound, it is wrong
  // (the robust loss has only damped it): drop the worst one and solve again from the start.
  for (;;) {
    std::map<int, NodeState> state;
    if (!SolveGraph(config_, poses_, edges_, fixed_, active, &state, report, why)) return false;
    int worst = -1;
    double worst_error = config_.loop_rejection_chi2;
    for (std::size_t e = 0; e < edges_.size(); ++e) {
      if (!edges_[e].loop || !active[e]) continue;
      const double error = WhitenedSquaredError(edges_[e], state);
      if (error > worst_error) {
        worst_error = error;
        worst = static_cast<int>(e);
      }
    }
    if (worst < 0) {
      for (auto& [id, node] : state) {
        Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
        T.linear() = node.q.normalized().toRotationMatrix();
        T.translation() = node.p;
        poses_[id] = T;
      }
      return true;
    }
    active[static_cast<std::size_t>(worst)] = false;
    report->rejected_loops.push_back(worst);
  }
}

}  // namespace objmap
