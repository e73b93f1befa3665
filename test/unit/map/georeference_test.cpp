// Georeference: zone texts, MGRS, the geodetic <-> map conversions and the convergence's sign.
#include "gmm_localization/core/map/georeference.h"

#include <cmath>

#include <gtest/gtest.h>

#include "support/test_georeference.h"

namespace gmm_localization {
namespace {

Georeference annArbor() { return testing::simulatorGeoreference(); }

TEST(Georeference, ParsesZoneTexts) {
  for (const char* text : {"17N", "17 n", "UTM 17N", "WGS84 / UTM zone 17N", "EPSG:32617", "32617",
                           " epsg : 32617 "}) {
    auto z = parseGridZone(text);
    ASSERT_TRUE(z.ok()) << text << ": " << z.error();
    EXPECT_EQ(z->zone, 17) << text;
    EXPECT_TRUE(z->north) << text;
    EXPECT_EQ(z->epsg(), 32617u);
  }
  auto south = parseGridZone("EPSG:32733");
  ASSERT_TRUE(south.ok());
  EXPECT_EQ(south->zone, 33);
  EXPECT_FALSE(south->north);
  EXPECT_EQ(south->name(), "33S");
  for (const char* bad : {"", "61N", "0N", "17", "EPSG:4326", "32661", "UTM 17X", "17N 18N"}) {
    auto z = parseGridZone(bad);
    EXPECT_FALSE(z.ok()) << bad;
    if (!z.ok()) {
      EXPECT_NE(z.error().find("names no WGS84 UTM zone"), std::string::npos);
    }
  }
}

TEST(Georeference, ZoneFromOldDatumText) {
  EXPECT_EQ(zoneFromDatumText("WGS84 / UTM zone 17N").zone, 17);
  EXPECT_EQ(zoneFromDatumText("heights above the geoid, EPSG:32733").zone, 33);
  EXPECT_FALSE(zoneFromDatumText("EPSG:32733").north);
  EXPECT_EQ(zoneFromDatumText("local frame of the test track").zone, 0);
}

TEST(Georeference, CentralMeridianAndRoundTrip) {
  Georeference g = annArbor();
  // On zone 17's central meridian (81 W) at the equator: E 500000, N 0, no convergence.
  g.origin_easting_m = 0.0;
  g.origin_northing_m = 0.0;
  g.origin_up_m = 0.0;
  auto p = geodeticToMap(g, {0.0, -81.0, 12.0}, 1e7);
  ASSERT_TRUE(p.ok()) << p.error();
  EXPECT_NEAR(p->x_m, 500000.0, 1e-6);
  EXPECT_NEAR(p->y_m, 0.0, 1e-6);
  EXPECT_NEAR(p->z_m, 12.0, 1e-12);
  EXPECT_NEAR(p->convergence_rad, 0.0, 1e-12);

  g = annArbor();
  for (double dx : {-3000.0, 0.0, 1234.5}) {
    for (double dy : {-2000.0, 0.0, 4321.25}) {
      auto geo = mapToGeodetic(g, dx, dy, 3.5);
      ASSERT_TRUE(geo.ok()) << geo.error();
      EXPECT_NEAR(geo->altitude_m, 253.5, 1e-9);
      auto back = geodeticToMap(g, *geo);
      ASSERT_TRUE(back.ok()) << back.error();
      EXPECT_NEAR(back->x_m, dx, 1e-6);
      EXPECT_NEAR(back->y_m, dy, 1e-6);
      EXPECT_NEAR(back->z_m, 3.5, 1e-9);
    }
  }
}

// map yaw = ENU yaw + convergence: true north (ENU yaw 90 deg) seen in the grid, west of the
// central meridian (Ann Arbor, 83.7 W in zone 17) and east of it.
TEST(Georeference, ConvergenceTurnsEnuYawIntoMapYaw) {
  const Georeference g = annArbor();
  for (double lon : {-83.74, -78.5}) {
    auto a = geodeticToMap(g, {42.28, lon, 0.0}, 1e6);
    auto b = geodeticToMap(g, {42.281, lon, 0.0}, 1e6);
    ASSERT_TRUE(a.ok() && b.ok());
    const double grid_yaw_of_true_north = std::atan2(b->y_m - a->y_m, b->x_m - a->x_m);
    EXPECT_NEAR(grid_yaw_of_true_north, M_PI / 2 + a->convergence_rad, 1e-4) << lon;
    EXPECT_GT(std::abs(a->convergence_rad), 0.01) << "a zone edge turns the grid ~1.7 deg";
  }
}

TEST(Georeference, RefusesBadInput) {
  Georeference none;
  EXPECT_FALSE(geodeticToMap(none, {42.0, -83.0, 0.0}).ok());
  Georeference text_only = annArbor();
  text_only.utm_zone = 0;
  EXPECT_FALSE(text_only.hasGrid());
  EXPECT_FALSE(geodeticToMap(text_only, {42.0, -83.0, 0.0}).ok());
  const Georeference g = annArbor();
  EXPECT_FALSE(geodeticToMap(g, {NAN, -83.0, 0.0}).ok());
  EXPECT_FALSE(geodeticToMap(g, {89.0, -83.0, 0.0}).ok());
  EXPECT_FALSE(geodeticToMap(g, {42.0, 200.0, 0.0}).ok());
  auto far = geodeticToMap(g, {45.0, -83.7, 0.0}, 1e5);  // ~300 km north
  ASSERT_FALSE(far.ok());
  EXPECT_NE(far.error().find("from the map origin"), std::string::npos);
  EXPECT_FALSE(mapToGeodetic(g, NAN, 0.0, 0.0).ok());
}

TEST(Georeference, Mgrs) {
  // GeographicLib's documented example: 33.3 N 44.4 E lies in the 1 km square 38SMB4484.
  auto m = parseMgrs("38SMB 44 84");
  ASSERT_TRUE(m.ok()) << m.error();
  EXPECT_EQ(m->zone.zone, 38);
  EXPECT_TRUE(m->zone.north);
  Georeference g;
  g.present = true;
  g.utm_zone = 38;
  g.origin_easting_m = m->easting_m;
  g.origin_northing_m = m->northing_m;
  auto p = geodeticToMap(g, {33.3, 44.4, 0.0});
  ASSERT_TRUE(p.ok()) << p.error();
  EXPECT_GE(p->x_m, 0.0);
  EXPECT_LT(p->x_m, 1000.0);
  EXPECT_GE(p->y_m, 0.0);
  EXPECT_LT(p->y_m, 1000.0);
  EXPECT_FALSE(parseMgrs("not an mgrs").ok());
  EXPECT_FALSE(parseMgrs("").ok());
  EXPECT_FALSE(parseMgrs("ZAA0000").ok());  // polar (UPS)
}

TEST(Georeference, Describe) {
  EXPECT_EQ(Georeference().describe(), "none");
  const std::string d = annArbor().describe();
  EXPECT_NE(d.find("UTM 17N (EPSG:32617)"), std::string::npos) << d;
  EXPECT_NE(d.find("E 277000.000"), std::string::npos) << d;
}

}  // namespace
}  // namespace gmm_localization
