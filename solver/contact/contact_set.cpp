#include "solver/contact/contact_set.hpp"

namespace stride {

int ContactSet::add(const Model& model, const std::string& frame, int dim, ReferenceFrame forces,
                    double kp, double kd) {
  if (!model.existFrame(frame))
    throw std::invalid_argument("ContactSet::add: model '" + model.name + "' has no frame '" +
                                frame + "'");
  if (dim != 3 && dim != 6)
    throw std::invalid_argument("ContactSet::add: contact '" + frame + "' has dimension " +
                                std::to_string(dim) + " (3 or 6)");
  if (model.frames[model.getFrameId(frame)].parentJoint == 0)
    throw std::invalid_argument("ContactSet::add: frame '" + frame +
                                "' is fixed to the world; a contact there constrains nothing");
  if (forces == ReferenceFrame::World)
    throw std::invalid_argument("ContactSet::add: contact forces are Local or LocalWorldAligned");
  if (!(kp >= 0.0) || !(kd >= 0.0))
    throw std::invalid_argument("ContactSet::add: Baumgarte gains must be non-negative");
  ContactModel c;
  c.name = frame;
  c.frame = model.getFrameId(frame);
  c.dim = dim;
  c.forces = forces;
  c.kp = kp;
  c.kd = kd;
  contacts_.push_back(c);
  active_.push_back(1);
  nc_ += dim;
  max_nc_ += dim;
  ++version_;
  return size() - 1;
}

bool ContactSet::setActive(int contact, bool active) {
  if (contact < 0 || contact >= size()) return false;
  if (isActive(contact) == active) return true;
  active_[contact] = active ? 1 : 0;
  nc_ += (active ? 1 : -1) * contacts_[contact].dim;
  ++version_;
  return true;
}

int ContactSet::find(const std::string& name) const {
  for (int c = 0; c < size(); ++c)
    if (contacts_[c].name == name) return c;
  return -1;
}

}  // namespace stride
