// Replaced by the simulator sources.
namespace gmm_localization {
namespace sim {
int simPlaceholder() { return 0; }
}  // namespace sim
}  // namespace gmm_localization
