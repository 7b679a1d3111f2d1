#pragma once
// The mechanism file (design §9, docs/file-format.md): YAML with declared units, read with
// yaml-cpp into a validated Model (SI inside). Every problem is one InputError naming
// file:line:column and the element; nothing is half-built.
#include <string>

#include "orthomech/model/model.hpp"

namespace orthomech {

// Reads and validates a mechanism file. Throws InputError.
[[nodiscard]] Model load_mechanism(const std::string& path);
// The same from text (`origin` is used as the file name in messages).
[[nodiscard]] Model parse_mechanism(const std::string& text, const std::string& origin);

}  // namespace orthomech
