#include "solver/multibody/srdf.hpp"

#include <tinyxml.h>

#include <algorithm>
#include <sstream>

#include "solver/multibody/lie_group.hpp"

namespace stride {

SrdfReport loadReferenceConfigurations(Model& model, const std::string& path) {
  TiXmlDocument doc(path);
  if (!doc.LoadFile()) {
    if (doc.ErrorId() == TiXmlBase::TIXML_ERROR_OPENING_FILE)
      throw UrdfError("SRDF '" + path + "': file does not exist or cannot be read");
    throw UrdfError("SRDF '" + path + "': malformed XML at line " + std::to_string(doc.ErrorRow()) +
                    ": " + doc.ErrorDesc());
  }
  const TiXmlElement* robot = doc.RootElement();
  if (!robot || std::string(robot->Value()) != "robot")
    throw UrdfError("SRDF '" + path + "': the root element must be <robot>");
  SrdfReport report;
  for (const TiXmlElement* gs = robot->FirstChildElement("group_state"); gs;
       gs = gs->NextSiblingElement("group_state")) {
    const char* state_name = gs->Attribute("name");
    const std::string line = " (line " + std::to_string(gs->Row()) + ")";
    if (!state_name) throw UrdfError("SRDF '" + path + "': <group_state> without a name" + line);
    Eigen::VectorXd q = neutral(model);
    for (const TiXmlElement* je = gs->FirstChildElement("joint"); je;
         je = je->NextSiblingElement("joint")) {
      const char* jname = je->Attribute("name");
      const char* value = je->Attribute("value");
      const std::string jline = " (line " + std::to_string(je->Row()) + ")";
      if (!jname || !value)
        throw UrdfError("SRDF '" + path + "': group_state '" + state_name +
                        "' has a <joint> without name or value" + jline);
      if (!model.existJoint(jname)) {
        if (std::find(report.ignored_joints.begin(), report.ignored_joints.end(), jname) ==
            report.ignored_joints.end())
          report.ignored_joints.push_back(jname);
        continue;
      }
      const Joint& j = model.joints[model.getJointId(jname)];
      std::istringstream in(value);
      std::vector<double> values;
      double x;
      while (in >> x) values.push_back(x);
      if (!in.eof() || static_cast<int>(values.size()) != j.nq)
        throw UrdfError("SRDF '" + path + "': group_state '" + state_name + "', joint '" + jname +
                        "' needs " + std::to_string(j.nq) + " number(s), got '" + value + "'" +
                        jline);
      for (int k = 0; k < j.nq; ++k) q[j.idx_q + k] = values[k];
    }
    normalize(model, q);
    model.referenceConfigurations[state_name] = q;
    report.states.push_back(state_name);
  }
  return report;
}

}  // namespace stride
