#!/usr/bin/env python3
"""What a warehouse system runs before a pick: the best box on a camera, in the robot's frame.

Asks a cornerpose server for the boxes on the newest frame of one of its
sources, takes the best-scoring one and prints its pose in the robot base
frame, given the hand-eye calibration base_T_camera:

  best_box_pose.py --server localhost:50051 --source cell --box carton_s \
      --robot_config deploy/config/robot_client.textproto        # the daemon's calibration
  best_box_pose.py --source cell --box 0.30,0.20,0.15 --base_pose_camera 0,-0.5,1.3,0,1,0,0

Exit status: 0 with a pose printed, 3 when the frame has no box, 1 when the
call fails (the gRPC status is printed), 2 for bad arguments.
"""

import argparse
import datetime
import json
import pathlib
import sys

import numpy as np
from google.protobuf import text_format

import cornerpose
from cornerpose._stubs import robot_client_config_pb2


def parse_box(text: str):
    parts = text.split(",")
    if len(parts) == 1:
        return text
    return tuple(float(p) for p in parts)


def hand_eye(args) -> np.ndarray:
    """base_T_camera from --base_pose_camera, or the daemon's configuration file."""
    if args.base_pose_camera:
        return cornerpose.as_transform([float(v) for v in args.base_pose_camera.split(",")])
    if args.robot_config:
        config = robot_client_config_pb2.RobotClientConfig()
        text_format.Parse(pathlib.Path(args.robot_config).read_text(), config)
        p, q = config.base_pose_camera.position, config.base_pose_camera.orientation
        return cornerpose.pose_matrix((p.x, p.y, p.z), (q.w, q.x, q.y, q.z))
    return np.eye(4)


def fmt(v) -> str:
    return "(" + ", ".join(f"{x:.4f}" for x in v) + ")"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server", default="localhost:50051", help="host:port of cornerpose_server")
    parser.add_argument("--source", required=True, help="a source the server serves (see ListSources)")
    parser.add_argument("--box", required=True, help="model name (carton_s, brick, ...) or l,b,h in metres")
    calib = parser.add_mutually_exclusive_group()
    calib.add_argument("--base_pose_camera", help="hand-eye calibration x,y,z,qw,qx,qy,qz (metres; "
                       "the camera in the robot base frame)")
    calib.add_argument("--robot_config", help="take base_pose_camera from the daemon's "
                       "configuration file (cornerpose.v1.RobotClientConfig text format)")
    parser.add_argument("--tls_ca", help="PEM CA that signed the server's certificate (TLS)")
    parser.add_argument("--tls_cert", help="PEM client certificate (mutual TLS)")
    parser.add_argument("--tls_key", help="PEM client key (mutual TLS)")
    parser.add_argument("--deadline_s", type=float, default=10.0, help="deadline of the call, seconds")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    args = parser.parse_args()

    try:
        base_T_camera = hand_eye(args)
        box = parse_box(args.box)
        client = cornerpose.Client(args.server, ca=args.tls_ca, cert=args.tls_cert,
                                   key=args.tls_key, timeout=args.deadline_s)
    except (ValueError, OSError, text_format.ParseError) as e:
        print(f"best_box_pose: {e}", file=sys.stderr)
        return 2
    with client:
        try:
            detection = client.detect(source=args.source, box=box)
        except ValueError as e:
            print(f"best_box_pose: {e}", file=sys.stderr)
            return 2
        except cornerpose.CornerposeError as e:
            print(f"best_box_pose: {e}", file=sys.stderr)
            return 1

    best = detection.best
    if best is None:
        print(f"best_box_pose: no box on {args.source} frame {detection.frame_id}", file=sys.stderr)
        return 3
    in_base = best.in_frame(base_T_camera)
    rotation = in_base.pose[:3, :3]
    if args.json:
        print(json.dumps({
            "source": detection.source, "frame_id": detection.frame_id,
            "capture_time_unix_nanos": detection.capture_time_unix_nanos,
            "score": best.score, "grasp_face": best.grasp_face,
            "base_T_box": in_base.pose.tolist(), "camera_T_box": best.pose.tolist(),
            "grasp_point": in_base.grasp_centre.tolist(), "grasp_normal": in_base.grasp_normal.tolist(),
        }))
        return 0
    captured = datetime.datetime.fromtimestamp(detection.capture_time_unix_nanos / 1e9)
    print(f"{detection.source} frame {detection.frame_id} (captured {captured:%H:%M:%S.%f}): "
          f"{len(detection.boxes)} boxes, detection {detection.timings.total_ms:.1f} ms")
    print(f"best box: score {best.score:.2f}, grasp face {best.grasp_face}")
    print(f"  camera frame: centre {fmt(best.position)} m")
    print(f"  base frame:   centre {fmt(in_base.position)} m")
    print(f"                rotation vector {fmt(cornerpose.rotation_vector(rotation))} rad, "
          f"zyx euler {fmt(cornerpose.euler_zyx_deg(rotation))} deg")
    print(f"  grasp point (base): {fmt(in_base.grasp_centre)} m, "
          f"face normal {fmt(in_base.grasp_normal)}")
    print("  base_T_box =")
    for row in in_base.pose:
        print("    [" + "  ".join(f"{x:9.5f}" for x in row) + "]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
