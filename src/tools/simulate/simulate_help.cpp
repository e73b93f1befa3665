// The --help text of `simulate` (kept apart from the parser; docs/simulator.md has the details).
#include "simulate/simulate_options.h"

namespace gmm_localization {
namespace tools {

const char* simulateHelp() {
  return R"(simulate: drive a simulated downtown with four Velodyne HDL-32Es and an Applanix-like INS.

Usage: simulate [options] (--bag FILE | --kitti DIR | --dry-run)

Town (the same seed and size give the same town in every pass):
  --town-seed N            town seed (1)
  --town-size M            street grid extent, both axes [m] (1200; >= 1000 for Downtown)
  --town-size-x M, --town-size-y M
  --block-min M, --block-max M   road spacing range [m] (90, 150)
  --building-density P     probability that a parcel holds a building (0.85)
  --tree-spacing M         street-tree spacing [m], 0 = none (11)
  --terrain-slope S        planar slope along x (0.010; y gets -0.6 x this)
Route:
  --route-seed N           route planner seed (7)
  --route-length M         route length [m] (3000)
  --route "i,j;i,j;..."    explicit intersections (adjacent nodes, no U-turns)
Pass:
  --pass TYPE              mapping | downtown | snowy (mapping)
  --pass-seed N            seed of what varies between passes (1)
  --moving-cars X          moving cars per km^2 (mapping 0, downtown 40, snowy 25)
  --pedestrians X          pedestrians per km^2 (mapping 0, downtown 150, snowy 60)
  --parked-keep P          share of parking slots unchanged from the mapping pass (0.6)
  --snowfall P             snowy: probability that a ray returns from a flake (0.015)
  --snow-depth MIN,MAX     snowy: snow cover depth range [m] (0.05,0.15)
  --aging MODE             none | realistic: the town a few months after the mapping drive
                           (construction sites, containers in parking slots, grown trees,
                           repaved stretches; downtown and snowy only) (none)
  --aging-sites-per-km X   realistic: fenced construction sites per km of road (1)
  --aging-containers-per-km X  realistic: shipping containers in parking slots per km (1.5)
  --aging-tree-share P     realistic: share of street trees with a grown crown (0.25)
  --aging-tree-growth MIN,MAX  realistic: crown growth outward and downward [m] (0.3,0.6)
  --aging-repaved-per-km X realistic: repaved 30-80 m stretches per km of road, half of them
                           without paint yet, half repainted 0.3-0.6 m to one side (0.5)
  --aging-seed N           realistic: seed of the changes (derived from pass and pass seed)
Segment (the first limit reached ends the segment):
  --start-offset M         start this far along the route [m] (0)
  --distance M             drive at most this far [m] (whole route)
  --duration S             drive at most this long [s] (whole route)
Sensors:
  --sensors 1|4            one roof-centre sensor, or four at the roof corners (4)
  --rate HZ                rotation rate 5..20 (10)
  --azimuth-step DEG       azimuth step; rounded to a multiple of the full-rate step
                           (0.166 deg at 10 Hz) (full rate)
  --range-noise M          1-sigma range noise (0.02)
  --dropout P              random dropout probability (0.005)
  --max-range M            (100)
  --mount-height M         sensor height above ground (1.95)
  --tilt DEG               outward tilt of the corner sensors (5)
  --extrinsic-error MODE   none | realistic: each sensor's true mount is off its nominal one
                           (rays are cast from the true mounts; merging, deskewing and
                           /tf_static use the nominal ones) (none)
  --extrinsic-error-m MIN,MAX    realistic: translation error range per sensor [m] (0.01,0.02)
  --extrinsic-error-deg MIN,MAX  realistic: rotation error range per sensor [deg] (0.1,0.2)
  --extrinsic-error-seed N realistic: seed of the errors (derived from pass and pass seed)
INS and ground truth:
  --ins-scale-error S      odometry distance scale error (0.002)
  --ins-heading-bias DEG   constant heading error (0.086)
  --ins-heading-rw DEG     heading random walk [deg/sqrt(s)] (0.0115)
  --ins-position-noise M   white noise on the reported position (0.005)
  --imu-gyro-noise R, --imu-accel-noise A   white noise [rad/s], [m/s^2] (0.002, 0.03)
  --odom-rate HZ (100)  --imu-rate HZ (200)  --gt-rate HZ (100)
  --noise-seed N           LIDAR noise seed (derived from pass and pass seed)
GNSS (bag only; docs/simulator.md "GNSS"):
  --gnss MODE              none | realistic: sensor_msgs/NavSatFix on /gnss/fix (frame
                           base_link), white noise + a first-order Gauss-Markov bias (none)
  --gnss-rate HZ (5)  --gnss-white M (0.5)  --gnss-bias M (1.0)  --gnss-bias-tau S (60)
                           per horizontal axis; vertical x1.5; reported sigma = sqrt(white^2 +
                           bias^2)
  --gnss-outage START_S:DURATION_S   no solution (status NO_FIX, NaN position) from START_S
                           after the segment start for DURATION_S; repeatable
  --gnss-seed N            (derived from pass and pass seed)
  --utm-zone Z, --georef-origin E,N,U   where the world sits on the Earth (17N,
                           277000,4686000,250); build the map with the same two options
Output:
  --bag FILE               write a rosbag (topics: /velodyne_points, /velodyne_N/velodyne_points
                           with --per-sensor-clouds, /ins/odom, /imu/data, /ground_truth/odom,
                           /tf, /tf_static)
  --lz4                    LZ4-compress bag chunks
  --per-sensor-clouds      also write the four per-sensor clouds (doubles the size)
  --no-merged              leave out /velodyne_points
  --epoch S                stamp = epoch + trajectory time (1600000000)
  --kitti DIR              write velodyne/NNNNNN.bin (x y z intensity, base_link, deskewed
                           with ground truth), poses.txt (3x4 base_link->map), times.txt
  --kitti-every N          write every N-th scan (1)
  --kitti-labels           also write labels/NNNNNN.label (uint8 per point)
  --map-pose-error MODE    poses.txt of --kitti: none (exact truth) | realistic (a SLAM back
                           end's: smooth drift pinned back at loop closures; the truth then goes
                           to poses_truth.txt as well) (none)
  --map-drift-per-100m M   realistic: drift random-walk std per axis after 100 m of path (0.03)
  --map-drift-deg-per-100m D  same for roll, pitch, yaw [deg] (0.05)
  --map-residual-m M       realistic: RMS position residual left after optimisation (0.05)
  --map-residual-deg D     realistic: RMS attitude residual [deg] (0.2)
  --map-loop-radius M      realistic: a revisit closer than M (after >= 50 m of path) closes a
                           loop (10)
  --map-pose-seed N        realistic: seed of the pose error (1)
  --threads N              ray-casting threads (2)
  --dry-run                build the town and route, print their summary, write nothing
  --quiet                  no progress lines
  --help
)";
}

}  // namespace tools
}  // namespace gmm_localization
