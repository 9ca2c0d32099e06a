#pragma once
// Configuration of the exploration planner (paper 003 section 4).

#include <cmath>

#include "common/config/config_error.h"

namespace rslam::explorer {

struct ExplorerConfig {
  double robot_radius_m = 0.12;       // obstacles are dilated by this (configuration space)
  int coarse_cell_factor = 4;         // exploration cell = factor x occupancy cell
  int min_unknown_cells_for_goal = 1; // occupancy cells unknown in a coarse cell to make it a goal
  // Uncertain cells (seen, between the free and occupied thresholds) make goals as unknown ones
  // do. Off, only cells never seen do: where a map correction keeps moving a wall, its cells stay
  // uncertain however often the robot looks (late in a 280 s demo run, 137 of 168 goals held
  // uncertain cells and nothing unseen). Either way the robot does not drive through them.
  bool uncertain_cells_are_goals = true;
  int pirouette_steps = 12;           // paper 003: 12 x 30 degrees
  bool pirouette_at_goal = true;      // paper 003: every plan ends with a pirouette
  int max_blocked_attempts = 3;       // refused moves near a goal before it is set aside (far ones: 3x)
  int blocked_goal_retries = 1;       // times such a goal is tried again before exploration ends
  // A goal set aside after refused moves takes the unseen cells within this of it along (they
  // come back with it on a retry), and cells never aimed at within this of those are no goals:
  // the way to each is the same (a round table's inside took four of 22 demo runs 80-140 s of
  // refusals, goal cell after goal cell, and one more to the time limit). 0 = the goal alone.
  double set_aside_radius_m = 0.5;
  bool squeeze_through_margin = true; // before calling exploration complete, plan through the margin
  // ... and if even that reaches no unknown space, take for goals the margin's cells that hold
  // unknown space but no obstacle of their own: the unknown past a gap narrower than the robot
  // plus both margins lies in the margin itself, so no goal was left past it (a demo run ended
  // with the space past a 0.6 m door unseen). One refused move on the narrow way to such a goal
  // sets it aside. Every cell so was a trip and a look, and a wall drawn with holes offers 20-40
  // of them: four of six demo runs reached the 280-s limit (session 32). Hence, and since a hole
  // in a drawn wall takes a look from next door but no way through, only cells whose centre lies
  // margin_goal_spare_m farther than the robot radius from every obstacle count: where the robot's
  // disc fits, as in a door or a passage's mouth (on 18 demo runs' last grids 4-16 reachable
  // cells against 30-58, the mouth of the passage south of the room among them in the three that
  // never entered it). On in the demo (tools/demo/MEASUREMENTS.md, session 38).
  bool margin_goals = false;
  double margin_goal_spare_m = 0.05;
  // Once squeezing through the margin, a step into or out of a margin cell costs this many times
  // a step over free cells (1..20; 1 = no dearer), and a straightened move crosses the margin only
  // where the grid path does: the plan keeps to free cells and takes the margin where the gap is.
  // At 1 such plans cut along walls all the way: in 42 demo runs 616 of their 738 plans were
  // refused (a bump or look before you move), half of those more than 1.5 m from the plan's end.
  int margin_step_cost = 1;
  // ... and if nothing is reachable even so, uncertain cells that join unknown space through
  // uncertain cells are goals: a frontier made wholly of cells seen too seldom to class (the far
  // edge of the camera's view) otherwise hides all that lies behind it. No effect with
  // uncertain_cells_are_goals.
  bool uncertain_frontier_goals = true;
  // Poses where straight moves started and ended remembered for the way back
  // (ExplorationPlanner::RecordMove; 0 = off).
  int way_back_moves = 20;
  bool straighten_paths = true;       // cut the grid path's corners where a straight move is clear
  // Before calling exploration complete, look once more on a finer exploration grid (this many
  // occupancy cells a side, dividing coarse_cell_factor; 0 = off) and explore on it to the end.
  // A coarse cell is free only if the whole cell clears the margin, so a gap 0.8 m wide (a round
  // table's opening in the demo world) often has no free cell across it: the space behind stays
  // unknown and exploration ends. Finer cells all the way are slower (more, smaller goals).
  int finishing_cell_factor = 0;
  int finishing_min_unknown_cells = 1;  // min_unknown_cells_for_goal on the finer grid
  // When nothing is left to explore, drive back to where exploration began (the pose of the first
  // plan) and look all round there before calling exploration complete: the views of the run's
  // first look close the loop of the whole run (active loop closing). Exploration goes on if the
  // corrected grid then shows unknown space again; at most three plans back are made (a grid that
  // changes on the way interrupts one). Off in the demo (tools/demo/MEASUREMENTS.md, session 41).
  bool return_to_start = false;
  // When nothing is left to explore, look from afar at goals set aside whose cells are still
  // unseen: drive over free cells (not through the margin) to a free cell set_aside_look_min_m..
  // set_aside_look_max_m from one, in plain sight of it, and turn to face it; each such goal once,
  // at most this many plans in all (0 = off). A goal in the margin set aside after a bump at a
  // wall's foot, or one a pirouette next door left unseen (the camera sees no floor closer than
  // its blind range), is often in view from a metre off. Off in the demo: 51 live runs with it
  // raised no coverage and ran 29% longer (tools/demo/MEASUREMENTS.md, session 62).
  int set_aside_looks = 0;
  double set_aside_look_min_m = 0.6;
  double set_aside_look_max_m = 1.6;

  template <class V>
  void VisitFields(V& v) {
    v("robot_radius_m", robot_radius_m, "robot radius; obstacles are dilated by it (m)");
    v("coarse_cell_factor", coarse_cell_factor, "exploration grid cell = this many occupancy cells");
    v("min_unknown_cells_for_goal", min_unknown_cells_for_goal,
      "unknown occupancy cells needed to make an exploration cell a goal");
    v("uncertain_cells_are_goals", uncertain_cells_are_goals,
      "cells seen but between the free and occupied thresholds make goals (else only cells never seen)");
    v("pirouette_steps", pirouette_steps, "rotations of one pirouette (360 / steps degrees each)");
    v("pirouette_at_goal", pirouette_at_goal,
      "end every plan with a pirouette (paper 003); false: only where unknown space is still next to the robot");
    v("max_blocked_attempts", max_blocked_attempts,
      "blocked moves towards one goal before it is set aside (within 1.5 m of where its plan ends; "
      "three times as many farther off)");
    v("blocked_goal_retries", blocked_goal_retries,
      "times goals set aside after blocked moves are tried again (after a look all round) before exploration ends");
    v("set_aside_radius_m", set_aside_radius_m,
      "a goal set aside after blocked moves takes the unseen cells within this radius along (m; 0 = the goal alone)");
    v("squeeze_through_margin", squeeze_through_margin,
      "when no unknown space is reachable over free cells, plan through the dilation margin (moves still keep the radius)");
    v("margin_goals", margin_goals,
      "when even squeezing through the margin reaches no unknown space, its cells that hold some (and no obstacle) are goals");
    v("margin_goal_spare_m", margin_goal_spare_m,
      "margin cells are such goals only where their centre is the robot radius plus this from every obstacle (m)");
    v("margin_step_cost", margin_step_cost,
      "once squeezing through the margin, a step into or out of it costs this many free steps (1 = no dearer)");
    v("uncertain_frontier_goals", uncertain_frontier_goals,
      "when no unknown space is reachable, uncertain cells that join some through uncertain cells are goals");
    v("way_back_moves", way_back_moves,
      "moves remembered to drive back along when the grid shuts the robot in (0 = off)");
    v("straighten_paths", straighten_paths,
      "skip a waypoint of the grid path where the straight move past it stays on the path's cells and is clear");
    v("finishing_cell_factor", finishing_cell_factor,
      "before calling exploration complete, go on with exploration cells of this many occupancy cells (0 = off)");
    v("finishing_min_unknown_cells", finishing_min_unknown_cells,
      "unknown occupancy cells needed to make a cell of that finer grid a goal");
    v("return_to_start", return_to_start,
      "when nothing is left to explore, drive back to where exploration began and pirouette there before completing");
    v("set_aside_looks", set_aside_looks,
      "when nothing is left to explore, plans that go and face a set-aside goal still unseen from afar (0 = off)");
    v("set_aside_look_min_m", set_aside_look_min_m, "nearest such a look is taken from (m)");
    v("set_aside_look_max_m", set_aside_look_max_m, "farthest such a look is taken from (m)");
  }
  void Validate() const {
    Require(std::isfinite(robot_radius_m) && robot_radius_m >= 0 && robot_radius_m < 10,
            "robot_radius_m", "must be in [0, 10)");
    Require(coarse_cell_factor >= 1 && coarse_cell_factor <= 64, "coarse_cell_factor", "must be 1..64");
    Require(min_unknown_cells_for_goal >= 1, "min_unknown_cells_for_goal", "must be >= 1");
    Require(pirouette_steps >= 1 && pirouette_steps <= 360, "pirouette_steps", "must be 1..360");
    Require(max_blocked_attempts >= 1, "max_blocked_attempts", "must be >= 1");
    Require(blocked_goal_retries >= 0 && blocked_goal_retries <= 100, "blocked_goal_retries", "must be 0..100");
    Require(std::isfinite(set_aside_radius_m) && set_aside_radius_m >= 0 && set_aside_radius_m <= 10,
            "set_aside_radius_m", "must be in [0, 10]");
    Require(finishing_cell_factor == 0 || (finishing_cell_factor >= 1 && finishing_cell_factor < coarse_cell_factor &&
                                           coarse_cell_factor % finishing_cell_factor == 0),
            "finishing_cell_factor", "must be 0 or a divisor of coarse_cell_factor smaller than it");
    Require(std::isfinite(margin_goal_spare_m) && margin_goal_spare_m >= 0 && margin_goal_spare_m <= 10,
            "margin_goal_spare_m", "must be in [0, 10]");
    Require(margin_step_cost >= 1 && margin_step_cost <= 20, "margin_step_cost", "must be 1..20");
    Require(way_back_moves >= 0 && way_back_moves <= 1000, "way_back_moves", "must be 0..1000");
    Require(finishing_min_unknown_cells >= 1, "finishing_min_unknown_cells", "must be >= 1");
    Require(set_aside_looks >= 0 && set_aside_looks <= 1000, "set_aside_looks", "must be 0..1000");
    Require(std::isfinite(set_aside_look_min_m) && set_aside_look_min_m >= 0, "set_aside_look_min_m",
            "must be >= 0");
    Require(std::isfinite(set_aside_look_max_m) && set_aside_look_max_m > set_aside_look_min_m &&
                set_aside_look_max_m <= 10,
            "set_aside_look_max_m", "must be greater than set_aside_look_min_m and at most 10");
  }
};

}  // namespace rslam::explorer
