"""The robots of bench/anchors: URDFs from the example-robot-data package installed in
the anchors' virtual environment, and the few adaptations both sides need."""
import os
import sysconfig
import xml.etree.ElementTree as ET
from dataclasses import dataclass


@dataclass
class Robot:
    key: str            # name on the command line (--robots)
    title: str          # name in the tables
    urdf: str           # file both sides load
    floating_base: bool


def example_robot_data_dir():
    """share/example-robot-data/robots of the cmeel prefix in this interpreter's site-packages."""
    site = sysconfig.get_paths()["purelib"]
    path = os.path.join(site, "cmeel.prefix", "share", "example-robot-data", "robots")
    if not os.path.isdir(path):
        raise SystemExit(f"anchors: example-robot-data not found at {path} (run bench/anchors/run)")
    return path


def panda_with_fixed_fingers(source, out_dir):
    """The Panda of example-robot-data with its two finger joints fixed: 7 DoF, the arm
    robodiff's reference robots use. (Its second finger mimics the first, which robodiff's
    URDF loader refuses and Pinocchio would count as a joint of its own.)"""
    tree = ET.parse(source)
    for joint in tree.getroot().iter("joint"):
        if "finger_joint" in joint.get("name", ""):
            joint.set("type", "fixed")
            for child in list(joint):
                if child.tag in ("mimic", "limit", "axis", "dynamics", "safety_controller"):
                    joint.remove(child)
    os.makedirs(out_dir, exist_ok=True)
    path = os.path.join(out_dir, "panda_fixed_fingers.urdf")
    tree.write(path)
    return path


# key -> (title, path under robots/, floating base)
CATALOGUE = {
    "panda": ("Panda (fingers fixed)", "panda_description/urdf/panda.urdf", False),
    "iiwa": ("iiwa", None, False),
    "talos": ("Talos fixed base", "talos_data/robots/talos_reduced.urdf", False),
    "talos_ff": ("Talos free-flyer", "talos_data/robots/talos_reduced.urdf", True),
    "solo12": ("Solo-12 free-flyer", "solo_description/robots/solo12.urdf", True),
}
DEFAULT_ROBOTS = "panda,iiwa,talos,talos_ff,solo12"


def resolve(keys, work_dir):
    """The Robot of each key; keys example-robot-data does not have are reported and left out."""
    base = example_robot_data_dir()
    robots = []
    for key in keys:
        if key not in CATALOGUE:
            raise SystemExit(f"anchors: unknown robot '{key}' (known: {', '.join(CATALOGUE)})")
        title, rel, floating = CATALOGUE[key]
        if rel is None:
            print(f"anchors: {key}: not in example-robot-data 4.3.0 (the pinned version): skipped")
            continue
        urdf = os.path.join(base, rel)
        if key == "panda":
            urdf = panda_with_fixed_fingers(urdf, os.path.join(work_dir, "robots"))
        robots.append(Robot(key, title, urdf, floating))
    return robots
