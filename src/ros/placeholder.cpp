// Replaced by the ROS layer sources.
namespace gmm_localization {
namespace node {
int rosPlaceholder() { return 0; }
}  // namespace node
}  // namespace gmm_localization
