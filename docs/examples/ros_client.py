#!/usr/bin/env python3
"""A rospy client of objmap_node: the objects of one class, then whether a box is free.

With the node running (docs/ros.md) and objmap's ROS paths set:

    source build/devel/setup.bash            # or PREFIX/setup.bash after `cmake --install`
    python3 docs/examples/ros_client.py --class cup
    python3 docs/examples/ros_client.py --class chair --box -1 -1 0 1 1 0.5

Without --box it asks about the box of the first object found, which holds that object's model
points, so the answer is "not free" and names the object. Exit code 0 on answers, 1 when the
node refuses a request (the reason is printed), 2 when it cannot be reached.
"""
import argparse
import sys

import rospy
from geometry_msgs.msg import Point
from objmap_msgs.srv import IsFree, IsFreeRequest, QueryObjects, QueryObjectsRequest


def point_text(point):
    return f"({point.x:.3f}, {point.y:.3f}, {point.z:.3f})"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--node", default="/objmap_node", help="the node's name (its namespace)")
    parser.add_argument("--class", dest="class_name", default="cup", help="a COCO class name")
    parser.add_argument("--box", nargs=6, type=float,
                        metavar=("MIN_X", "MIN_Y", "MIN_Z", "MAX_X", "MAX_Y", "MAX_Z"),
                        help="the box to ask IsFree about, world frame, metres")
    parser.add_argument("--timeout", type=float, default=10.0,
                        help="seconds to wait for the node's services")
    # rospy.myargv drops ROS remapping arguments (name:=value) before argparse sees them.
    args = parser.parse_args(rospy.myargv(argv=sys.argv)[1:])

    rospy.init_node("objmap_client_example", anonymous=True)
    query_objects_name = args.node + "/query_objects"
    is_free_name = args.node + "/is_free"
    try:
        rospy.wait_for_service(query_objects_name, timeout=args.timeout)
        rospy.wait_for_service(is_free_name, timeout=args.timeout)
    except rospy.ROSException:
        print(f"{args.node} does not answer (is it running, and is ROS_MASTER_URI right?)",
              file=sys.stderr)
        return 2
    query_objects = rospy.ServiceProxy(query_objects_name, QueryObjects)
    is_free = rospy.ServiceProxy(is_free_name, IsFree)

    # Objects of the class, by id; only those in the inventory (include_unconfirmed false).
    found = query_objects(QueryObjectsRequest(class_name=args.class_name))
    if not found.ok:
        print(f"query_objects refused: {found.error}", file=sys.stderr)
        return 1
    print(f"{len(found.objects)} {args.class_name} (map version {found.map_version})")
    for obj in found.objects:
        print(f"  object {obj.id}: {obj.class_name}, confidence {obj.confidence:.2f}, "
              f"{obj.observations} observations, centroid {point_text(obj.centroid)}")

    if args.box:
        region_min, region_max = Point(*args.box[:3]), Point(*args.box[3:])
    elif found.objects:
        region_min, region_max = found.objects[0].bounds_min, found.objects[0].bounds_max
    else:
        print("no box to ask about: give --box")
        return 0
    answer = is_free(IsFreeRequest(region_min=region_min, region_max=region_max,
                                   unknown_is_free=False))
    if not answer.ok:
        print(f"is_free refused: {answer.error}", file=sys.stderr)
        return 1
    objects = " ".join(str(i) for i in answer.object_ids) or "none"
    print(f"box {point_text(region_min)} - {point_text(region_max)}: "
          f"{'free' if answer.free else 'not free'} ({answer.occupied} occupied, "
          f"{answer.unknown} unknown voxels; objects: {objects})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
