"""A URDF's inertial parameters in the regressor's convention, read with plain Python:
the truth that identify_from_csv.py compares its estimate with.

Per moving joint, in the model's joint order, 10 numbers of the composite body the joint
moves (its child link and every link fixed to it), in the joint's frame:
[m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz], c the centre of mass and I
the rotational inertia about the frame's origin (docs/conventions.md, "The regressor").
Fixed-base robots only (the root link's inertia moves with no joint).
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from typing import Sequence

import numpy as np


def rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """URDF's roll-pitch-yaw: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    (cr, cp, cy), (sr, sp, sy) = np.cos(rpy), np.sin(rpy)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _origin(element) -> tuple[np.ndarray, np.ndarray]:
    """An <origin>'s rotation and translation (identity when absent)."""
    origin = None if element is None else element.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    xyz = [float(x) for x in origin.get("xyz", "0 0 0").split()]
    rpy = [float(x) for x in origin.get("rpy", "0 0 0").split()]
    return rpy_matrix(rpy), np.array(xyz)


def _link_body(link, rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """One link's 10 parameters in a frame where the link's frame is at (rotation, translation)."""
    inertial = link.find("inertial")
    if inertial is None:
        return np.zeros(10)
    mass = float(inertial.find("mass").get("value"))
    r_i, p_i = _origin(inertial)
    values = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
    local = np.array([[values["ixx"], values["ixy"], values["ixz"]],
                      [values["ixy"], values["iyy"], values["iyz"]],
                      [values["ixz"], values["iyz"], values["izz"]]])
    r = rotation @ r_i
    com = translation + rotation @ p_i
    inertia = r @ local @ r.T + mass * (com @ com * np.eye(3) - np.outer(com, com))
    return np.array([mass, *(mass * com), inertia[0, 0], inertia[1, 0], inertia[1, 1],
                     inertia[2, 0], inertia[2, 1], inertia[2, 2]])


def inertial_parameters(urdf_path, joint_names: Sequence[str]) -> np.ndarray:
    """The 10 * len(joint_names) parameters of the composite bodies moved by these joints."""
    robot = ElementTree.parse(urdf_path).getroot()
    links = {link.get("name"): link for link in robot.findall("link")}
    joints = {joint.get("name"): joint for joint in robot.findall("joint")}
    children: dict[str, list] = {}
    for joint in joints.values():
        children.setdefault(joint.find("parent").get("link"), []).append(joint)

    def composite(link_name: str, rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
        total = _link_body(links[link_name], rotation, translation)
        for joint in children.get(link_name, []):
            if joint.get("type") == "fixed":
                r_j, p_j = _origin(joint)
                total = total + composite(joint.find("child").get("link"),
                                          rotation @ r_j, translation + rotation @ p_j)
        return total

    parameters = []
    for name in joint_names:
        if name not in joints:
            raise ValueError(f"joint '{name}' is not in {urdf_path}")
        parameters.append(composite(joints[name].find("child").get("link"), np.eye(3), np.zeros(3)))
    return np.concatenate(parameters)
