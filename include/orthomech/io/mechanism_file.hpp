#pragma once
// The mechanism file (docs/design.md §9, docs/file-format.md): YAML with declared units, read with
// yaml-cpp into a validated Model (SI inside). Every problem is one InputError naming
// file:line:column and the element; nothing is half-built.
#include <string>
#include <vector>

#include "orthomech/model/model.hpp"

namespace orthomech {

// One `--set PATH=VALUE` (docs/cli.md "Changing the file from the command line"): the value, in
// the file's units and YAML syntax, replaces the element at PATH before the file is read, and is
// validated exactly as the file is (a problem names the --set).
struct FileChange {
  std::string path;   // map keys and list item names (or indices) joined by '.'; or a parameter
  std::string value;  // YAML text: 4000, [90, 0], 600rpm, 2*L
};
// "PATH=VALUE" split at the first '='. Throws std::invalid_argument when either side is empty.
[[nodiscard]] FileChange parse_file_change(const std::string& text);

// The text of the single value at `path` (as for a FileChange) of a mechanism file's text, as
// written there ("30", "a/2"). Throws InputError naming origin and path.
[[nodiscard]] std::string file_value(const std::string& text, const std::string& origin,
                                     const std::string& path);

// The text with the value at each change's path replaced in place by the change's value (every
// other byte kept: comments, order, units), checked by reading each value back. The values must
// be written as plain scalars there. Throws InputError naming origin and path.
[[nodiscard]] std::string with_file_values(const std::string& text, const std::string& origin,
                                           const std::vector<FileChange>& changes);

// Reads and validates a mechanism file, with `changes` applied in order. Throws InputError.
[[nodiscard]] Model load_mechanism(const std::string& path,
                                   const std::vector<FileChange>& changes = {});
// The same from text (`origin` is used as the file name in messages).
[[nodiscard]] Model parse_mechanism(const std::string& text, const std::string& origin,
                                    const std::vector<FileChange>& changes = {});

}  // namespace orthomech
