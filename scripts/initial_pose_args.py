#!/usr/bin/python3
"""Prints the replay launch's initial-pose arguments for a simulator bag: its first
/ground_truth/odom pose moved by 2 m, -1.5 m and 2 deg, as a GPS fix would be (the matcher then
searches its 25 m x 25 m x +-15 deg window around it). Usage: initial_pose_args.py BAG
Prints nothing when the bag has no ground truth."""
import math
import sys

import rosbag

with rosbag.Bag(sys.argv[1]) as bag:
    for _, m, _ in bag.read_messages(topics=["/ground_truth/odom"]):
        p, q = m.pose.pose.position, m.pose.pose.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        print("initial_x:=%.3f initial_y:=%.3f initial_z:=%.3f initial_yaw:=%.4f" % (
            p.x + 2.0, p.y - 1.5, p.z, yaw + math.radians(2.0)))
        break
