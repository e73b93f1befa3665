// build_map's usage text (--help).
#include <string>

#include "build_map/build_map_options.h"

namespace gmm_localization {
namespace tools {
namespace {

const char* helpTemplate() {
  return R"(build_map: build a Gaussian mixture map (Wolcott & Eustice 2015, section III) from LIDAR data.

Usage: build_map --output DIR INPUT [options]

Input (exactly one kind):
  --pcd FILE|DIR           a point-cloud map (PCD v0.5-0.7: ascii, binary or binary_compressed;
                           x y z of any numeric type, F4, F8, I/U 1-8 bytes, read in double),
                           e.g. from LIO-SAM, FAST-LIO or hdl_graph_slam. Repeat for several
                           files; a directory stands for every *.pcd in it, sorted by name
                           (Autoware's tiles). Every file is checked before the build starts
                           (header, data size, compressed stream): a bad file is an error
                           naming it. No sensor origins, so the range filter does not apply.
                           Files are streamed in batches of --pcd-batch points (1000000).
    --transform X,Y,Z,ROLL,PITCH,YAW   or X,Y,Z,QX,QY,QZ,QW: the files' frame in the world
                           frame [m, deg], applied to every point first (e.g. to level
                           FAST-LIO's first-IMU frame); --offset is subtracted after it:
                           p_map = transform * p_file - offset, in double, then float
    --max-abs-z M          drop (and count) points with map-frame |z| above M, e.g. junk
                           returns far above the map (3000); non-finite points are dropped too
  --kitti DIR              KITTI-style scans: DIR/NNNNNN.bin, DIR/NNNNNN/points.bin or
                           DIR/velodyne/NNNNNN.bin, float32 little-endian records
    --kitti-fields F       auto | xyz | xyzi (auto: xyzi under velodyne/, else from the file
                           size, 12 vs 16 bytes per point; a multiple of 48 bytes is ambiguous)
    --poses FILE           poses: KITTI 3x4 rows (line i = scan i) or 'id x y z qx qy qz qw'
                           lines (default DIR/graph.txt, else DIR/poses.txt)
    --scans LIST           scans to use, e.g. 0,2,4-9 (default: every scan with a pose)
    --kitti-calib FILE     KITTI odometry calib.txt: poses are camera-0 poses; map frame =
                           first Velodyne frame (z up)
  --bag FILE               a rosbag with sensor_msgs/PointCloud2 scans and their poses
    --cloud-topic T        (/velodyne_points)
    --pose-topic T         nav_msgs/Odometry, geometry_msgs/PoseStamped or
                           PoseWithCovarianceStamped, interpolated to each scan's stamp
                           (/ground_truth/odom)
    --pose-tf PARENT,CHILD instead of a pose topic: the poses of CHILD in PARENT from /tf
                           (e.g. map,base_link; chains such as map -> odom -> base_link and
                           /tf_static edges are composed)
    --extrinsic X,Y,Z,ROLL,PITCH,YAW   or X,Y,Z,QX,QY,QZ,QW: the cloud frame in the pose's
                           child frame [m, deg]. Default: composed from /tf_static (any chain
                           of static transforms between the two frames), identity if the
                           frames are equal.
    --max-pose-gap S       skip scans whose bracketing poses are further apart (0.25 s)
    --every N              use every N-th scan (1)
    --time-field NAME      the per-point time used to deskew each scan with the interpolated
                           poses. Default: the matcher's reader's choice of time, t and
                           timestamp (velodyne, Ouster, Hesai, RoboSense, Livox; relative or
                           absolute, s or ns). Clouds without times, or with times that make
                           no sense (counted), are not deskewed
    --no-deskew            ignore per-point times
  --synthetic-street M     a generated straight street of M metres (facades, parked cars,
                           trees, poles, awnings) scanned by a simulated 32-laser LIDAR
    --seed N (1)  --scan-spacing M (1.0)  --azimuth-step DEG (0.2)

Output:
  --output DIR, --out DIR  map directory (created); refuses to replace a map unless --overwrite
  --overwrite              replace the map in DIR: the new map is built beside it and swapped
                           in when complete; a failed or killed build leaves the old map intact

Map (defaults follow the paper):
  --resolution M           cell size, in @RESOLUTION_RANGE@ (0.2)
  --tile-size N            cells per tile edge (320)
  --origin X,Y             map-frame corner of cell (0, 0) (0,0)
  --k-max K                most Gaussians per cell, 1..3 (2)
  --criterion C            model selection: icl | bic (icl; see em_fitter.h)
  --sigma-floor M          smallest sigma, ~ sensor range noise (0.03)
  --blur-sigma M           Gaussian blur with neighbouring columns (0.1; 0 = off)
  --blur-radius N          blur half-width in cells (1)
  --z-bin M                z histogram bin (0.01)
  --min-own-points N       returns a cell needs in its own column (1)

Layer (the manifest records it; map_info prints it):
  --layer L                height | reflectivity (height). reflectivity: Levinson and Thrun's
                           ground-reflectivity map (the baseline of the paper's Table I): only
                           ground returns are kept, and each cell holds a mixture over their
                           intensity x --reflectivity-scale instead of their heights. Needs
                           per-point intensities (--kitti-fields xyzi, a PointCloud2
                           `intensity` field, the synthetic street) and scan poses, so not
                           --pcd. Its place is beside the height map, e.g.
                             build_map --kitti DIR --kitti-fields xyzi --layer reflectivity
                               --output MAP/reflectivity
    --ground-height M      z of the ground in the vehicle frame (0): for --kitti the scans'
                           frame (0 for simulate's base_link on the ground, about -1.73 for
                           KITTI's Velodyne frame), for --bag the poses' frame (e.g.
                           base_link), for --synthetic-street base_link on the road
    --ground-band MIN,MAX  a ground return's levelled height lies within [MIN, MAX] of the
                           ground height (-0.3,0.3)
    --ground-range M       ... and within M of the vehicle, horizontally (40)
    --reflectivity-scale M metres per intensity unit (0.02: intensities 0..255 -> 0..5.1 m)

Filters (applied in this order; counts in the summary):
  --min-range M, --max-range M   distance from the scan's sensor origin (1, 120); not for PCD
  --min-z M, --max-z M     map-frame height band (unbounded; heights in either layer)
  ground returns           --layer reflectivity only: see above
  --voxel M                per-scan voxel pre-filter edge, 0 = off (0)
  --offset X,Y,Z           subtracted from every input point and pose, e.g. a UTM origin, to
                           keep map coordinates small (in double, before float: a float32 map
                           keeps centimetres only within 131 km of its origin); recorded as
                           the map's georeference origin

Georeference (map_info prints it; the GNSS initializer needs a zone):
  --utm-zone ZONE          WGS84 UTM zone of the input's grid: 17N, 33S, EPSG:32617
  --epsg CODE              the same as an EPSG code (32601-32660 north, 32701-32760 south)
  --georef-origin E,N,U    the input is already local: the map origin's grid coordinates
  --mgrs-origin REF[,U]    the same as an MGRS reference (names the zone too)
  --datum TEXT             free text kept with the map, e.g. "heights above the geoid"

Resources:
  --threads N              fitting threads (2)
  --temp-dir DIR           where the spill files go (default: inside --output)
  --spill-buffer-mb MB     in-memory spill buffers (256)
  --no-deflate             store tiles uncompressed
  --quiet                  no progress bar
  --help
)";
}

}  // namespace

const char* buildMapHelp() {
  static const std::string help = [] {
    std::string h = helpTemplate();
    const std::string key = "@RESOLUTION_RANGE@";
    h.replace(h.find(key), key.size(), resolutionRange());
    return h;
  }();
  return help.c_str();
}

}  // namespace tools
}  // namespace gmm_localization
