// Stride as a library: loads a robot with the config loader, runs its contact dynamics once and
// one FDDP iteration of a short standing problem, and checks the results' sizes and finiteness;
// plays the robot's trot on the planner's contact timeline (Stride::locomotion). Also checks a
// truncated message against the LCM types' checks (Stride::messages).
// Usage: stride-consumer ROBOT.yaml; exit 0 when every check passes. Objects holding Eigen members
// are made in the library and destroyed here (Robot, ContactData, the knots): with an Eigen
// alignment that differs between the two, this is where it crashed (issue 17).
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <vector>

// Stride's headers as a user includes them: under stride/ (short_include.cpp, which must not
// compile, tries the in-tree form). The LCM types too (<stride/robot_state_t.hpp>).
#include <stride/config/robot_config.hpp>
#include <stride/locomotion/contact_timeline.hpp>
#include <stride/locomotion/gait.hpp>
// The planner's whole header chain (the gait generator's, the terrain's included) through the view.
#include <stride/locomotion/locomotion_problem.hpp>
#include <stride/messages/validate.hpp>
#include <stride/robot_state_t.hpp>
#include <stride/solver/contact/contact_dynamics.hpp>
#include <stride/solver/contact/knot_dynamics.hpp>
#include <stride/solver/ddp/solver.hpp>
#include <stride/solver/multibody/model.hpp>
#include <stride/solver/ocp/knot.hpp>
#include <stride/solver/ocp/residual_state.hpp>

using namespace stride;

namespace {

int check(bool ok, const char* what) {
  std::printf("%-44s %s\n", what, ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}

int run(const char* yaml) {
  const Robot robot = loadRobot(yaml);
  const Model& model = robot.model;
  const int nu = actuatedDimension(model);
  ContactSet contacts;
  for (const ContactSpec& c : robot.contacts)
    contacts.add(model, c.frame, c.dim, ReferenceFrame::LocalWorldAligned);
  std::printf("%s: nq %d, nv %d, nu %d, %d contacts\n", robot.name.c_str(), model.nq, model.nv, nu,
              contacts.size());

  // Contact dynamics at the default posture, at rest, without torques.
  Data data(model);
  ContactData cdata(model, contacts);
  const Eigen::VectorXd v = Eigen::VectorXd::Zero(model.nv);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(model.nv);
  const ContactStatus cs = contactDynamics(model, data, contacts, cdata, robot.default_q, v, tau);
  int failures = check(cs == ContactStatus::Ok, "contact dynamics: status");
  failures += check(cdata.nc == contacts.maxNc() && cdata.ddq.size() == model.nv,
                    "contact dynamics: sizes");
  failures += check(cdata.ddq.allFinite() && cdata.lambda.head(cdata.nc).allFinite(),
                    "contact dynamics: finite");

  // One FDDP iteration: 20 knots of 10 ms on all contacts, holding the default posture.
  Eigen::VectorXd x0(model.nq + model.nv);
  x0 << robot.default_q, v;
  auto workspace = std::make_shared<SharedWorkspace>(model, 1);
  std::vector<std::unique_ptr<ActionModel>> running;
  for (int k = 0; k < 20; ++k) {
    auto knot = std::make_unique<KnotModel>(model, contacts, 0.01, workspace);
    knot->costs().add("state", std::make_unique<StateResidual>(model, nu, x0),
                      Activation::quadratic(2 * model.nv), 1.0);
    knot->costs().add("control", std::make_unique<ControlResidual>(model, nu),
                      Activation::quadratic(nu), 1e-3);
    running.push_back(std::move(knot));
  }
  auto terminal = std::make_unique<TerminalModel>(model);
  terminal->costs().add("state", std::make_unique<StateResidual>(model, 0, x0),
                        Activation::quadratic(2 * model.nv), 10.0);
  ShootingProblem problem(x0, std::move(running), std::move(terminal));
  Solver solver(problem, SolverKind::Fddp);
  const SolveStatus status = solver.solve(1);
  std::printf("FDDP: %s, cost %.6g, gap %.3g, step %.3g\n", toString(status), solver.cost(),
              solver.gap(), solver.statsCount() > 0 ? solver.stats()[0].step : 0.0);
  failures +=
      check(status != SolveStatus::NonFinite && solver.iterations() == 1, "solver: one iteration");
  failures +=
      check(solver.xs().size() == 21 && solver.us().size() == 20 && solver.us()[0].size() == nu,
            "solver: trajectory sizes");
  bool finite = std::isfinite(solver.cost());
  for (const Eigen::VectorXd& x : solver.xs()) finite = finite && x.allFinite();
  for (const Eigen::VectorXd& u : solver.us()) finite = finite && u.allFinite();
  failures += check(finite, "solver: finite");
  failures +=
      check(solver.statsCount() == 1 && solver.stats()[0].step > 0.0, "solver: a step was taken");

  // The planner: the robot's trot (4 feet: the front-left and hind-right pair lifts first) on a
  // contact timeline.
  ContactTimeline timeline(contacts);
  timeline.reset(timeline.addPattern(makeGaitPattern("trot", GaitTiming{0.1, 0.2}, robot.contacts)),
                 0.0);
  failures += check(contacts.size() == 4 && timeline.mask(0.05) == 0b1111u &&
                        timeline.mask(0.15) == 0b0110u && timeline.mask(0.45) == 0b1001u,
                    "locomotion: a trot's contact timeline");

  // The generated LCM types and their checks: four bytes are no command.
  const unsigned char truncated[4] = {1, 2, 3, 4};
  failures += check(robot_state_t::getHash() != 0 &&
                        msg::checkCommandWire(truncated, sizeof truncated) != msg::Reject::None,
                    "messages: a truncated command is rejected");
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s ROBOT.yaml\n", argv[0]);
    return 2;
  }
  try {
    return run(argv[1]);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
