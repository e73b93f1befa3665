// build_map's georeference options -> the map's Georeference.
#include "build_map/build_map_georeference.h"

#include <gtest/gtest.h>

namespace gmm_localization {
namespace tools {
namespace {

TEST(BuildMapGeoreference, NoOptionsNoGeoreference) {
  auto g = resolveGeoreference({});
  ASSERT_TRUE(g.ok());
  EXPECT_FALSE(g->present);
}

TEST(BuildMapGeoreference, OffsetWithZone) {
  GeoreferenceArgs a;
  a.offset_m = Eigen::Vector3d(277000, 4686000, 250);
  a.utm_zone = "17N";
  auto g = resolveGeoreference(a);
  ASSERT_TRUE(g.ok()) << g.error();
  EXPECT_TRUE(g->hasGrid());
  EXPECT_EQ(g->utm_zone, 17);
  EXPECT_EQ(g->origin_northing_m, 4686000);
  EXPECT_EQ(g->datum, "WGS84 / UTM zone 17N");
  a.utm_zone.clear();
  a.epsg = "32733";
  g = resolveGeoreference(a);
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g->utm_zone, 33);
  EXPECT_FALSE(g->utm_north);
}

TEST(BuildMapGeoreference, MgrsOrigin) {
  GeoreferenceArgs a;
  a.mgrs_origin = "38SMB4484,31.5";
  auto g = resolveGeoreference(a);
  ASSERT_TRUE(g.ok()) << g.error();
  EXPECT_EQ(g->utm_zone, 38);
  EXPECT_EQ(g->origin_up_m, 31.5);
  EXPECT_GT(g->origin_easting_m, 100000);
  a.utm_zone = "17N";
  g = resolveGeoreference(a);
  ASSERT_FALSE(g.ok());
  EXPECT_NE(g.error().find("names zone 38N"), std::string::npos) << g.error();
  a.utm_zone.clear();
  a.mgrs_origin = "38SMB4484,high";
  EXPECT_FALSE(resolveGeoreference(a).ok());
  a.mgrs_origin = "no such reference";
  EXPECT_FALSE(resolveGeoreference(a).ok());
}

TEST(BuildMapGeoreference, ConflictsAndTextOnly) {
  GeoreferenceArgs a;
  a.offset_m = Eigen::Vector3d(1, 2, 3);
  a.georef_origin_m = Eigen::Vector3d(1, 2, 3);
  auto g = resolveGeoreference(a);
  ASSERT_FALSE(g.ok());
  EXPECT_NE(g.error().find("give one"), std::string::npos);
  a = {};
  a.utm_zone = "17N";
  a.epsg = "EPSG:32618";
  EXPECT_FALSE(resolveGeoreference(a).ok());
  a = {};
  a.utm_zone = "99Q";
  g = resolveGeoreference(a);
  ASSERT_FALSE(g.ok());
  EXPECT_NE(g.error().find("--utm-zone"), std::string::npos);
  // The old way: a datum text naming the zone.
  a = {};
  a.offset_m = Eigen::Vector3d(630084, 4833438, 76.5);
  a.datum = "WGS84 / UTM zone 32N";
  g = resolveGeoreference(a);
  ASSERT_TRUE(g.ok());
  EXPECT_EQ(g->utm_zone, 32);
  // An origin without a zone: text only, no grid.
  a.datum.clear();
  g = resolveGeoreference(a);
  ASSERT_TRUE(g.ok());
  EXPECT_TRUE(g->present);
  EXPECT_FALSE(g->hasGrid());
}

}  // namespace
}  // namespace tools
}  // namespace gmm_localization
