// Replaced by the nodelet entry points.
namespace gmm_localization {
namespace node {
int nodeletPlaceholder() { return 0; }
}  // namespace node
}  // namespace gmm_localization
