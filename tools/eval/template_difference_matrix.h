#pragma once
// The place matcher under evaluation, behind one function so the harness never knows what it
// is: every reference image is learnt as a template (TemplateLibrary::Learn), and each query
// gives one row of differences to all of them (TemplateLibrary::Differences), so
// D(i, j) = difference of query i to the template of reference j.
//
// The matcher is the project's template learner, rslam::templates::TemplateLibrary, configured
// from the `templates:` section of a preset (deploy/presets/<name>.yaml). When this library is
// built without rslam_templates, a clearly named fallback (patch-normalised SAD, 8x8 blocks, see
// patch_normalised_sad.h) stands in and the preset is ignored; PlaceMatcherName() says which.

#include <yaml-cpp/yaml.h>

#include <opencv2/core.hpp>

#include <span>
#include <string>

#include "tools/eval/difference_matrix.h"

namespace rslam::eval {

// "template_library" or "patch_sad_fallback".
std::string PlaceMatcherName();

// preset: the YAML root of a preset (a null node = the matcher's defaults). Throws
// rslam::ConfigError for a bad `templates:` section, std::invalid_argument for bad images.
DifferenceMatrix BuildTemplateDifferences(std::span<const cv::Mat> references, std::span<const cv::Mat> queries,
                                          const YAML::Node& preset);

}  // namespace rslam::eval
