// SPDX-License-Identifier: Apache-2.0
// core/model_units.hpp — the unit of every key of a robot parameter file, by generic path
// ("joints[].friction.f_c": list indices as []), in the words urt_model_print uses. The overlay
// loader checks an entry's `unit:` against it. Context: non-RT.
#ifndef URT_CORE_MODEL_UNITS_HPP
#define URT_CORE_MODEL_UNITS_HPP

#include <string>

namespace urt::core {

// The unit of a config key, or nullptr when the path is not a key of the file.
const char *config_unit(const std::string &generic_path);

}  // namespace urt::core

#endif
