#include "tools/eval/template_difference_matrix.h"

#include <stdexcept>

#include "common/config/config_loader.h"
#include "tools/eval/patch_normalised_sad.h"

#if RSLAM_EVAL_HAVE_TEMPLATES
#include "services/templates/template_config.h"
#include "services/templates/template_library.h"
#endif

namespace rslam::eval {

#if RSLAM_EVAL_HAVE_TEMPLATES

std::string PlaceMatcherName() { return "template_library"; }

DifferenceMatrix BuildTemplateDifferences(std::span<const cv::Mat> references, std::span<const cv::Mat> queries,
                                          const YAML::Node& preset) {
  if (references.empty() || queries.empty()) throw std::invalid_argument("no reference or no query images");
  templates::TemplateConfig config;
  if (preset && !preset.IsNull()) LoadConfigSection(preset, "templates", config);
  templates::TemplateLibrary library(config);
  for (const cv::Mat& reference : references) library.Learn(reference);
  DifferenceMatrix differences(static_cast<Eigen::Index>(queries.size()), static_cast<Eigen::Index>(library.size()));
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const std::vector<double> row = library.Differences(queries[i]);
    if (row.size() != library.size()) throw std::logic_error("TemplateLibrary::Differences returned a short row");
    for (std::size_t j = 0; j < row.size(); ++j) {
      differences(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = row[j];
    }
  }
  return differences;
}

#else

std::string PlaceMatcherName() { return "patch_sad_fallback"; }

DifferenceMatrix BuildTemplateDifferences(std::span<const cv::Mat> references, std::span<const cv::Mat> queries,
                                          const YAML::Node& /*preset: TemplateConfig unavailable*/) {
  return BaselinePatchSad(references, queries);
}

#endif

}  // namespace rslam::eval
