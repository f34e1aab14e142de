// Laser-tracker traces.
#include "deflex/model/tracker_trace.hpp"

namespace deflex {

double trace_length_m(const TrackerTrace& trace) {
  double length = 0.0;
  for (std::size_t i = 1; i < trace.size(); ++i) {
    length += (trace[i].p_m - trace[i - 1].p_m).norm();
  }
  return length;
}

}  // namespace deflex
