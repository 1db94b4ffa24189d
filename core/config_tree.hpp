// SPDX-License-Identifier: Apache-2.0
// core/config_tree.hpp — the YAML tree a robot parameter file is read into before validation:
// the file with its includes resolved, then each overlay, then each --set override applied,
// every value remembering the file and line it came from (Origin), so that model_load.cpp's
// validation names them. Internal to the core. Context: non-RT; failures are thrown as
// LoadError and stop at the loader's C entry point.
#ifndef URT_CORE_CONFIG_TREE_HPP
#define URT_CORE_CONFIG_TREE_HPP

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "config_field.hpp"

namespace urt::core::config {

// A unit an overlay states for a key the unit table does not know: refused after validation,
// which names an unknown key first.
struct PendingUnit {
  std::string file, key;
  int line;
};

// The tree of the config at `path` with its includes resolved, then `overlays` and then
// `overrides` ("key=value") applied, each list NULL-terminated or NULL. `origin` (made for
// `path`) learns where every value came from; units to refuse after validation go to `pending`.
YAML::Node read_tree(Origin *origin, const char *path, const char *const *overlays,
                     const char *const *overrides, std::vector<PendingUnit> *pending);

// The unit of a key written as overlays and --set write it ("joints.1.motor.kt"), or NULL for
// a malformed key or one the unit table does not know.
const char *key_unit(const char *key);

// Throws LoadError "file:line: key: reason" (URT_ECONFIG).
[[noreturn]] void fail_at(const std::string &file, int line, const std::string &key,
                          const std::string &reason);

}  // namespace urt::core::config

#endif  // URT_CORE_CONFIG_TREE_HPP
