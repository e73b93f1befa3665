#include "gmm_localization/ros/cloud_merger_options.h"

#include <set>

#include "gmm_localization/ros/params.h"

namespace gmm_localization {
namespace node {

CloudMergerOptions loadCloudMergerOptions(const ParamSource& pnh) {
  CloudMergerOptions o;
  o.input_topics = param(pnh, "input_topics", o.input_topics);
  if (o.input_topics.empty()) {
    throw ConfigError("parameter " + pnh.resolveName("input_topics") +
                      " must list at least one topic");
  }
  std::set<std::string> unique;
  for (const std::string& t : o.input_topics) {
    if (t.empty() || !unique.insert(t).second) {
      throw ConfigError("parameter " + pnh.resolveName("input_topics") +
                        " has an empty or repeated topic '" + t + "'");
    }
  }
  o.output_frame = param<std::string>(pnh, "output_frame", o.output_frame);
  if (o.output_frame.empty()) throw ConfigError("parameter output_frame must not be empty");
  o.sync.sensors = o.input_topics.size();
  o.sync.max_wait_s = param(pnh, "max_wait_s", o.sync.max_wait_s, 0.001, 10.0);
  o.sync.max_stamp_spread_s =
      param(pnh, "max_stamp_spread_s", o.sync.max_stamp_spread_s, 0.001, 10.0);
  o.sync.backwards_reset_s =
      param(pnh, "backwards_reset_s", o.sync.backwards_reset_s, 0.001, 3600.0);
  requireValid("synchronisation options", o.sync.validate());
  o.expected_rate_hz = param(pnh, "expected_rate_hz", o.expected_rate_hz, 0.1, 1000.0);
  o.input_queue_size = param(pnh, "input_queue_size", o.input_queue_size, 1, 100);
  return o;
}

}  // namespace node
}  // namespace gmm_localization
