// Deprecated: deflex/paths/key_value_spec.hpp moved to deflex/text/key_value_spec.hpp in deflex 0.2.0 (CHANGELOG.md);
// this forwarding header goes in 0.3.0. Include the new one (define DEFLEX_NO_DEPRECATED_HEADER_WARNINGS to silence the
// warning meanwhile).
#pragma once
#ifndef DEFLEX_NO_DEPRECATED_HEADER_WARNINGS
#pragma GCC warning \
    "deflex/paths/key_value_spec.hpp is deprecated: include deflex/text/key_value_spec.hpp (this header goes in deflex 0.3)"
#endif
#include "deflex/text/key_value_spec.hpp"
