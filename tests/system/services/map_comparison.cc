#include "tests/system/services/map_comparison.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "services/experience_map/experience_action_message.h"

namespace rslam::system_test {

MapRecord MapOfRunner(const run::RatSlamRunner& runner) {
  msg::ExperienceMap message;
  experience_map::FillMapMessage(runner.experience_map(), message);
  return MapOfSnapshot(message);
}

MapRecord MapOfSnapshot(const msg::ExperienceMap& snapshot) {
  return {snapshot.experiences, snapshot.links, snapshot.current_experience_id};
}

MapDifference CompareMaps(const MapRecord& expected, const MapRecord& actual, double tolerance) {
  MapDifference result;
  std::ostringstream out;
  int reported = 0;
  const auto number = [&](const std::string& what, double a, double b) {
    const double d = std::abs(a - b);
    result.max_abs_difference = std::max(result.max_abs_difference, std::isnan(d) ? INFINITY : d);
    if (!(d <= tolerance) && reported++ < 10) out << what << ": expected " << a << ", got " << b << " (diff " << d << ")\n";
  };
  const auto exact = [&](const std::string& what, int64_t a, int64_t b) {
    if (a != b && reported++ < 10) out << what << ": expected " << a << ", got " << b << "\n";
  };
  out.precision(17);
  exact("experience count", static_cast<int64_t>(expected.experiences.size()), static_cast<int64_t>(actual.experiences.size()));
  exact("link count", static_cast<int64_t>(expected.links.size()), static_cast<int64_t>(actual.links.size()));
  exact("current experience", expected.current_experience_id, actual.current_experience_id);
  for (std::size_t i = 0; i < std::min(expected.experiences.size(), actual.experiences.size()); ++i) {
    const auto& a = expected.experiences[i];
    const auto& b = actual.experiences[i];
    const std::string at = "experience " + std::to_string(i) + " ";
    exact(at + "id", a.id, b.id);
    exact(at + "template", a.template_id, b.template_id);
    number(at + "x", a.x_m, b.x_m);
    number(at + "y", a.y_m, b.y_m);
    number(at + "theta", a.theta_rad, b.theta_rad);
    number(at + "pc_x", a.pc_x, b.pc_x);
    number(at + "pc_y", a.pc_y, b.pc_y);
    number(at + "pc_th", a.pc_th, b.pc_th);
  }
  for (std::size_t i = 0; i < std::min(expected.links.size(), actual.links.size()); ++i) {
    const auto& a = expected.links[i];
    const auto& b = actual.links[i];
    const std::string at = "link " + std::to_string(i) + " ";
    exact(at + "from", a.from_id, b.from_id);
    exact(at + "to", a.to_id, b.to_id);
    exact(at + "closes_loop", a.closes_loop, b.closes_loop);
    number(at + "distance", a.distance_m, b.distance_m);
    number(at + "heading", a.heading_rad, b.heading_rad);
    number(at + "facing", a.facing_rad, b.facing_rad);
    number(at + "travel time", a.travel_time_s, b.travel_time_s);
  }
  if (reported > 10) out << "... " << reported - 10 << " more differences\n";
  result.description = out.str();
  return result;
}

std::string Summary(const MapRecord& map) {
  std::set<uint32_t> templates;
  for (const auto& e : map.experiences) templates.insert(e.template_id);
  const auto closures = std::count_if(map.links.begin(), map.links.end(), [](const auto& l) { return l.closes_loop; });
  return std::to_string(map.experiences.size()) + " experiences, " + std::to_string(map.links.size()) + " links (" +
         std::to_string(closures) + " closing loops), " + std::to_string(templates.size()) + " templates";
}

}  // namespace rslam::system_test
