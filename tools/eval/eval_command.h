#pragma once
// `rslam eval`: evaluation subcommands.
//
//   rslam eval vpr --reference DIR --query DIR [--tolerance N] [--sequence L]
//                  [--contrast-window W] [--preset P | --config FILE] [--matcher template|baseline]
//                  [--limit N] [--json]
//     Visual place recognition on frame-aligned image sets (same file name = same place),
//     prints recall@1 and recall@100%precision (vpr_evaluation.h).
//   rslam eval trajectory --estimate FILE.csv --ground-truth FILE.csv [--no-scale]
//                         [--max-stamp-gap-ms T] [--json]
//     Absolute trajectory error after similarity alignment (trajectory_alignment.h); CSV format
//     in trajectory_csv.h (stamp_ns,x,y[,theta]).
//   rslam eval odometry RECORDING.mcap [--config FILE] [--set section.key=value ...] [--robot ID]
//                       [--json]
//     A simulated run's odometry read again (odometry_replay.h): the recording's frames rendered
//     anew at its sim/ground_truth and read with the config's odometry section; dead-reckoning ATE,
//     heading error, turns misread, and how many recorded velocities the replay does not give back.
//
// Failures (unreadable input, bad config) print the reason to err and throw CLI::RuntimeError
// (exit code 1; CLI11's exit() prints nothing for it).

#include <CLI/CLI.hpp>

#include <ostream>

namespace rslam::eval {

// Adds `eval` with subcommands `vpr`, `trajectory` and `odometry` to the rslam app; results go to out,
// failure reasons to err. Both streams must outlive the app.
void RegisterEvalCommand(CLI::App& rslam, std::ostream& out, std::ostream& err);
// Results go to std::cout, failures to std::cerr.
void RegisterEvalCommand(CLI::App& rslam);

}  // namespace rslam::eval
