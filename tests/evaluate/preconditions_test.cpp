// Broken preconditions of the evaluation refused in every build type (the tests run in Release in
// CI): a trace with a sample that is not finite where a plane is fitted (laps, the mean closed path),
// lap thresholds that are not numbers in range, and a time search range that is not a number. Before,
// one NaN sample made the plane NaN: best_fit_plane, split_laps and directed_laps answered from it
// without an error, and mean_closed_path blamed the path for not going round its centre; a NaN turn
// threshold dropped every lap, a NaN reversal threshold switched reversals off; and a NaN search
// range or centre was ignored, so every offset was searched where the caller asked for a window.
#include <functional>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "deflex/evaluate/lap_split.hpp"
#include "deflex/evaluate/time_alignment.hpp"
#include "deflex/text/errors.hpp"
#include "evaluate/synthetic_paths.hpp"
#include "support/error_of.hpp"

namespace deflex {
namespace {

TrackerTrace three_laps_round_a_circle() { return test::circle(0.1, Vector3(1.5, 0.0, 1.0), 3000, 3.0); }

TEST(EvaluatePreconditions, ANonFiniteSampleIsRefusedWhereAPlaneIsFittedNamingTheSample) {
  TrackerTrace trace = three_laps_round_a_circle();
  ASSERT_FALSE(split_laps(trace).laps.empty());
  trace[1234].p_m.z() = kNaN;
  for (const auto& call : {std::function<void()>([&] { (void)best_fit_plane(trace); }),
                           std::function<void()>([&] { (void)split_laps(trace); }),
                           std::function<void()>([&] { (void)directed_laps(trace); }),
                           std::function<void()>([&] { (void)mean_closed_path(trace); })}) {
    const std::string error = test::error_of(call);
    EXPECT_NE(error.find("sample 1234"), std::string::npos) << error;
    EXPECT_NE(error.find("not finite"), std::string::npos) << error;
  }
}

TEST(EvaluatePreconditions, LapThresholdsOutOfRangeAreRefused) {
  const TrackerTrace trace = three_laps_round_a_circle();
  for (const double turn : {kNaN, 0.0, -1.0, 7.0}) {
    const std::string error = test::error_of([&] { (void)split_laps(trace, turn); });
    EXPECT_NE(error.find("min_turn_rad"), std::string::npos) << turn << ": " << error;
  }
  for (const double reversal : {kNaN, 0.0, -0.1, std::numeric_limits<double>::infinity()}) {
    const std::string error = test::error_of([&] { (void)split_laps(trace, 0.9 * 2.0 * kPi, reversal); });
    EXPECT_NE(error.find("reversal_rad"), std::string::npos) << reversal << ": " << error;
  }
  EXPECT_FALSE(split_laps(trace, 0.95 * 2.0 * kPi).laps.empty());
}

TEST(EvaluatePreconditions, ATimeSearchRangeOrCentreThatIsNotANumberIsRefused) {
  // A command that moves, and a measured run of it: the check comes before any search.
  const TrackerTrace commanded = test::circle(0.1, Vector3(1.5, 0.0, 1.0), 2000, 1.0);
  const TrackerTrace measured = commanded;
  TimeAlignmentOptions o;
  o.search_s = kNaN;
  std::string error = test::error_of([&] { (void)align_time(measured, commanded, o); });
  EXPECT_NE(error.find("search_s"), std::string::npos) << error;
  o.search_s = 0.5;
  o.centre_s = kNaN;
  error = test::error_of([&] { (void)align_time(measured, commanded, o); });
  EXPECT_NE(error.find("centre_s"), std::string::npos) << error;
}

TEST(EvaluatePreconditions, AnAlignmentThatIsNotANumberIsRefusedWhenTimesAreMapped) {
  // Before: a NaN offset (an alignment of the caller's own) turned every time stamp into NaN.
  const TrackerTrace trace = test::circle(0.1, Vector3(1.5, 0.0, 1.0), 100, 1.0);
  TimeAlignment alignment;
  alignment.offset_s = 0.25;
  EXPECT_NEAR(to_program_time(trace, alignment)[10].t_s, trace[10].t_s + 0.25, 1e-15);
  alignment.drift = kNaN;
  const std::string error = test::error_of([&] { (void)to_program_time(trace, alignment); });
  EXPECT_NE(error.find("drift"), std::string::npos) << error;
}

}  // namespace
}  // namespace deflex
