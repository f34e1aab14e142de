// A process that pushes on the simulated arm's TCP with a force that depends on where the arm truly
// is: the LDBB's bar (its length strokes the piston against the seal's friction), and a cutting
// process whose force follows the true, deflected tool position. The tick's coupled solve
// (coupled_tick.hpp) asks it for its wrench at trial positions of the arm within a tick and settles
// the tick with the position it found, so no force of the cell lags the arm by a tick.
#pragma once

#include "deflex/model/types.hpp"

namespace deflex::cell {

/// Where the arm's true TCP is in a tick: position (m, base frame, as the tracker and the process see
/// it, drift included), orientation (base frame) and velocity over the tick (m/s).
struct TcpMotion {
  Vector3 position_m = Vector3::Zero();
  Matrix3 orientation = Matrix3::Identity();
  Vector3 velocity_m_s = Vector3::Zero();
};

/// Thread safety: one thread at a time (a process has its own history and random draws).
class ProcessForce {
 public:
  virtual ~ProcessForce() = default;
  /// Moves the process's own time on by one tick of `dt_s` (its drive, its noise): once a tick,
  /// before the tick's solve.
  virtual void advance(double dt_s) = 0;
  /// The wrench (N, Nm at the TCP, base frame) the process puts on the arm if its TCP moves as
  /// `motion` this tick. A trial: changes nothing, so the solve may ask any number of times.
  [[nodiscard]] virtual Wrench wrench_at(const TcpMotion& motion) const = 0;
  /// Ends the tick with the TCP moving as `motion`: the process's history (a seal's friction, a
  /// tool's engagement) moves on from there.
  virtual void commit(const TcpMotion& motion) = 0;
};

}  // namespace deflex::cell
