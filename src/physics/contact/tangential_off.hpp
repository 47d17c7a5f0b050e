// Tangential part, off: no shear force and no history (every ks is 0 and no law is Hertz-Mindlin).
#pragma once

namespace trubal {

struct TangentialOff {
  static constexpr bool kOn = false;
};

}  // namespace trubal
