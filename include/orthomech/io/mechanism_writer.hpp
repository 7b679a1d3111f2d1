#pragma once
// Writing mechanism files (issue 4: `assemble --write`). The file is edited, not regenerated:
// only the numbers of each body's `pose:` change, so comments, units, order and every other key
// stay as the user wrote them. Poses are written in the file's declared units with 17
// significant digits (reading them back gives the same doubles up to one rounding of the unit
// conversion). A spatial file (dimension 3) gets each body's `position` numbers and its
// orientation as `{quaternion: [e0, e1, e2, e3]}` (another orientation form is replaced by it, a
// missing one added; docs/cli.md "Writing a spatial file").
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

// The text of a mechanism file (`text`, parsed from `origin`) with every body pose replaced by
// the pose in q. Throws InputError when the text is not the file the model was read from, when a
// pose is shared through a YAML alias (editing it would change the other uses), or when the
// edited text would not re-read as the model with the new poses (checked by reading it back; a
// spatial file must also close its joints at the written pose).
// A UTF-8 byte order mark and CRLF line ends are kept.
[[nodiscard]] std::string replace_design_poses(const std::string& text, const std::string& origin,
                                               const Model& model, const VecX& q);

// replace_design_poses with what it did to the expressions of the parameters: a pose number
// written as an expression (`pose: [a/2, 0, 0]`, docs/file-format.md "Parameters") that the
// assembly did not move (within 1e-13 m or rad of the mechanism's size) keeps its text; one that
// moved is written as a number and named in `replaced_expressions` ("body 'coupler': pose x: the
// expression 'b/2' is now 41.5 (the assembly moved it)").
struct PoseEdit {
  std::string text;
  std::vector<std::string> replaced_expressions;
};
[[nodiscard]] PoseEdit edit_design_poses(const std::string& text, const std::string& origin,
                                         const Model& model, const VecX& q);

// The mass, centre of mass (body frame, m) and inertia about it (kg·m²) of a planar body, as
// `balance --write` gives them to a body with its counterweight.
struct MassEdit {
  int body = -1;
  double mass = 0.0;
  Vec2 com = Vec2::Zero();
  double inertia = 0.0;
};
// The text of a planar mechanism file with those bodies' `mass:`, `com:` and `inertia:` numbers
// replaced in place (the file's units, 15 significant digits; an expression there becomes a
// number), every other byte kept. Throws InputError when the text is not the model's file, a
// body lacks one of the three keys, a number is shared through a YAML alias, or the edited text
// would not read back as the model with the new mass properties.
[[nodiscard]] std::string edit_mass_properties(const std::string& text, const std::string& origin,
                                               const Model& model,
                                               const std::vector<MassEdit>& changes);

}  // namespace orthomech
