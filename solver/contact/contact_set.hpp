#pragma once
// Rigid contacts on frames: 3D point contacts (the frame origin is held still) and 6D surface
// contacts (the whole frame is held). The constraint on the contact's acceleration, in the
// contact frame's LOCAL coordinates (paper eq. 10, with Baumgarte stabilization):
//   point:   a_lin + ω x ν + kd ν + kp R^T (p - p_ref) = 0     (classical acceleration)
//   surface: a + kd v + kp log6(M_ref^-1 M) = 0                 (spatial acceleration)
// Forces are solved in LOCAL coordinates; a contact may report them LOCAL or LOCAL_WORLD_ALIGNED
// (rotated to world axes) - the motion is the same either way.
//
// A ContactSet is built once with every contact a problem may use; contacts are switched on and
// off per phase without reallocating anything.

#include <cstdint>
#include <string>
#include <vector>

#include "solver/multibody/model.hpp"

namespace stride {

// The contact limit: the most contacts a robot may have in Stride, one number for every module. A
// contact is bit c of a phase's mask (the solver's, the gait generator's, the wire's int32 masks:
// policy_t.phase, mpc_status_t.phase, horizon_t.contact_mask; messages/validate.hpp,
// kContactMaskBits) and flag c of robot_state_t.contact (the controller and stride-teleop refuse a
// state with more flags). Here, the lowest floor all of them include: solver/ knows nothing of the
// messages, and the receivers all link the solver.
constexpr int kMaxContacts = 8;

struct ContactModel {
  std::string name;
  int frame = -1;
  int dim = 3;                                    // 3: point, 6: surface
  ReferenceFrame forces = ReferenceFrame::Local;  // Local or LocalWorldAligned
  double kp = 0.0, kd = 0.0;                      // Baumgarte gains
  SE3 reference;  // the contact placement the position term pulls to (used when kp > 0)
};

class ContactSet {
 public:
  // Adds a contact on a frame (throws std::invalid_argument for an unknown frame, a frame fixed to
  // the world, a dimension other than 3 or 6, or a World force frame). Returns its index. Setup
  // only.
  int add(const Model& model, const std::string& frame, int dim,
          ReferenceFrame forces = ReferenceFrame::Local, double kp = 0.0, double kd = 0.0);

  // Switches a contact on or off; false (and no change) for an index out of range.
  bool setActive(int contact, bool active);
  bool isActive(int contact) const { return active_[contact] != 0; }
  void setReference(int contact, const SE3& placement) {
    contacts_[contact].reference = placement;
    ++version_;
  }
  int size() const { return static_cast<int>(contacts_.size()); }
  const ContactModel& operator[](int contact) const { return contacts_[contact]; }
  int find(const std::string& name) const;  // -1 when absent

  int nc() const { return nc_; }         // stacked dimension of the active contacts
  int maxNc() const { return max_nc_; }  // of all contacts
  // Changes with every change to the set (a contact added, switched, its reference moved): a
  // contact solve kept for later (KnotModel) is valid only while the version is the same.
  std::uint64_t version() const { return version_; }

 private:
  std::vector<ContactModel> contacts_;
  std::vector<char> active_;
  int nc_ = 0, max_nc_ = 0;
  std::uint64_t version_ = 0;
};

}  // namespace stride
