#include "gmm_localization/sim/materials.h"

#include <cstddef>

namespace gmm_localization {
namespace sim {

const MaterialResponse& materialResponse(Material m) {
  // Diffuse reflectivities near 905 nm (asphalt ~0.05-0.1, concrete ~0.25, vegetation ~0.3-0.5
  // in NIR but porous, snow ~0.6-0.8, retroreflective sheeting saturates the receiver). Fresh
  // asphalt is black bitumen over the aggregate; it lightens as traffic wears the binder off,
  // so a new surface returns about half the power of a worn one.
  static const MaterialResponse kTable[] = {
      {0.07f, 0.0f, 0.000f},   // kAsphalt
      {0.22f, 0.0f, 0.000f},   // kConcrete
      {0.25f, 0.0f, 0.000f},   // kGrass
      {0.14f, 0.0f, 0.000f},   // kWall
      {0.32f, 0.0f, 0.000f},   // kWallBright
      {0.05f, 0.0f, 0.450f},   // kGlass
      {0.10f, 0.0f, 0.000f},   // kRoofing
      {0.20f, 0.0f, 0.000f},   // kFabric
      {0.12f, 0.0f, 0.000f},   // kBark
      {0.30f, 0.40f, 0.050f},  // kFoliage
      {0.20f, 0.0f, 0.000f},   // kMetal
      {0.95f, 0.0f, 0.000f},   // kSign
      {0.18f, 0.0f, 0.000f},   // kCarPaint
      {0.04f, 0.0f, 0.350f},   // kCarGlass
      {0.04f, 0.0f, 0.000f},   // kTire
      {0.15f, 0.0f, 0.000f},   // kPerson
      {0.60f, 0.0f, 0.000f},   // kSnow
      {0.50f, 0.0f, 0.000f},   // kLaneMarking
      {0.035f, 0.0f, 0.000f},  // kAsphaltNew
  };
  static_assert(sizeof(kTable) / sizeof(kTable[0]) == static_cast<std::size_t>(Material::kCount),
                "material table out of date");
  return kTable[static_cast<std::size_t>(m)];
}

}  // namespace sim
}  // namespace gmm_localization
