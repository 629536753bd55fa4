"""The MuJoCo model of a bench/anchors robot: the same physics as Pinocchio's model of
the same URDF, for the semi-implicit Euler step rows (euler_step_value, euler_step_jacobian).

The URDF is copied without its visual and collision geometry (meshes MuJoCo may not read)
and without joint dynamics (damping, friction), and its fixed joints are merged here the
way Pinocchio merges them (the child's inertia added to the parent's): MuJoCo checks each
body's inertia before it fuses static bodies, and Talos has a fixed link whose inertia
alone fails that check. MuJoCo then loads the URDF (mjSpec), gets one motor actuator per
joint (gear 1, no control limit), semi-implicit Euler at dt = 0.01, gravity -9.81 z,
contacts and constraints off, no damping, armature or friction loss, and is saved as a
binary model (MJB) for mujoco_bench."""
import os
import xml.etree.ElementTree as ET

import numpy as np

DT = 0.01  # the step of the euler_step rows


def rpy_matrix(rpy):
    """URDF's rpy: R = Rz(yaw) Ry(pitch) Rx(roll)."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def matrix_rpy(R):
    """The inverse of rpy_matrix (any of the angles at the pitch singularity)."""
    pitch = np.arctan2(-R[2, 0], np.hypot(R[0, 0], R[1, 0]))
    if np.hypot(R[0, 0], R[1, 0]) < 1e-12:
        return np.array([np.arctan2(-R[1, 2], R[1, 1]), pitch, 0.0])
    return np.array([np.arctan2(R[2, 1], R[2, 2]), pitch, np.arctan2(R[1, 0], R[0, 0])])


def numbers(text, default):
    return np.array([float(x) for x in text.split()]) if text else np.array(default, dtype=float)


def origin_of(element):
    """(position, rotation) of an element's <origin> (identity when absent)."""
    o = element.find("origin")
    if o is None:
        return np.zeros(3), np.eye(3)
    return numbers(o.get("xyz"), [0, 0, 0]), rpy_matrix(numbers(o.get("rpy"), [0, 0, 0]))


def set_origin(element, position, rotation):
    o = element.find("origin")
    if o is None:
        o = ET.SubElement(element, "origin")
    o.set("xyz", " ".join(repr(float(x)) for x in position))
    o.set("rpy", " ".join(repr(float(x)) for x in matrix_rpy(rotation)))


def inertial_of(link):
    """(mass, centre of mass, inertia about it) in the link's frame; zero when absent."""
    inertial = link.find("inertial")
    if inertial is None:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com, R = origin_of(inertial)
    mass = float(inertial.find("mass").get("value"))
    i = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
    I = np.array([[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]], [i["ixz"], i["iyz"], i["izz"]]])
    return mass, com, R @ I @ R.T


def set_inertial(link, mass, com, inertia):
    old = link.find("inertial")
    if old is not None:
        link.remove(old)
    if mass <= 0:
        return
    inertial = ET.SubElement(link, "inertial")
    ET.SubElement(inertial, "origin", xyz=" ".join(repr(float(x)) for x in com), rpy="0 0 0")
    ET.SubElement(inertial, "mass", value=repr(float(mass)))
    names = {"ixx": (0, 0), "ixy": (0, 1), "ixz": (0, 2), "iyy": (1, 1), "iyz": (1, 2), "izz": (2, 2)}
    ET.SubElement(inertial, "inertia", {k: repr(float(inertia[r, c])) for k, (r, c) in names.items()})


def merged_inertia(a, b):
    """Two bodies' (mass, com, inertia about com), in one frame, as one body."""
    (ma, ca, Ia), (mb, cb, Ib) = a, b
    mass = ma + mb
    if mass <= 0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = (ma * ca + mb * cb) / mass
    shift = lambda m, d: m * (d @ d * np.eye(3) - np.outer(d, d))  # noqa: E731 (parallel axes)
    return mass, com, Ia + shift(ma, ca - com) + Ib + shift(mb, cb - com)


def merge_fixed_joints(root):
    """Merges each fixed joint's child link into its parent, as Pinocchio does: the
    child's inertia moves to the parent, the child's joints hang from the parent."""
    links = {link.get("name"): link for link in root.findall("link")}
    while True:
        fixed = next((j for j in root.findall("joint") if j.get("type") == "fixed"), None)
        if fixed is None:
            return
        parent, child = fixed.find("parent").get("link"), fixed.find("child").get("link")
        p, R = origin_of(fixed)  # the child's frame in the parent's
        mass, com, inertia = inertial_of(links[child])
        moved = (mass, p + R @ com, R @ inertia @ R.T)
        set_inertial(links[parent], *merged_inertia(inertial_of(links[parent]), moved))
        for joint in root.findall("joint"):
            if joint.find("parent").get("link") == child:
                jp, jR = origin_of(joint)
                set_origin(joint, p + R @ jp, R @ jR)
                joint.find("parent").set("link", parent)
        root.remove(fixed)
        root.remove(links.pop(child))


def plain_urdf(urdf, out_path):
    """A copy of the URDF with inertials and moving joints only (see the module's text)."""
    tree = ET.parse(urdf)
    root = tree.getroot()
    for link in root.iter("link"):
        for child in list(link):
            if child.tag in ("visual", "collision"):
                link.remove(child)
    for joint in root.iter("joint"):
        for child in list(joint):
            if child.tag in ("dynamics", "mimic", "safety_controller", "calibration"):
                joint.remove(child)
    merge_fixed_joints(root)
    for element in [e for e in root if e.tag in ("transmission", "gazebo")]:
        root.remove(element)
    tree.write(out_path)
    return out_path


def build(urdf, work_dir, pinocchio_joint_names):
    """Writes the robot's MuJoCo model (MJB) into work_dir; returns (path, MuJoCo's joint
    names in its own order). Joints are matched by name with Pinocchio's (all must be hinges)."""
    import mujoco

    os.makedirs(work_dir, exist_ok=True)
    plain = plain_urdf(urdf, os.path.join(work_dir, "mujoco_plain.urdf"))
    spec = mujoco.MjSpec.from_file(plain)
    joints = [j.name for j in spec.joints]
    if sorted(joints) != sorted(pinocchio_joint_names):
        raise ValueError(f"MuJoCo's joints {joints} are not Pinocchio's {pinocchio_joint_names}")
    for joint in spec.joints:
        if joint.type != mujoco.mjtJoint.mjJNT_HINGE:
            raise ValueError(f"joint {joint.name}: only hinge joints are supported by the MuJoCo side")
        joint.damping, joint.stiffness = [0, 0, 0], [0, 0, 0]  # polynomial coefficients in MuJoCo 4
        joint.armature, joint.frictionloss, joint.springyield = 0, 0, 0
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_FALSE
    for name in pinocchio_joint_names:  # controls in Pinocchio's order
        spec.add_actuator(name=f"motor_{name}", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT,
                          ctrllimited=mujoco.mjtLimited.mjLIMITED_FALSE,
                          forcelimited=mujoco.mjtLimited.mjLIMITED_FALSE)
    spec.option.timestep = DT
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.gravity = [0, 0, -9.81]
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT | mujoco.mjtDisableBit.mjDSBL_CONSTRAINT
    model = spec.compile()
    order = [model.joint(i).name for i in range(model.njnt)]
    # The binary model keeps every number exact; to_xml() writes 6 significant digits,
    # which moves the step by 1e-6 (the XML is kept for reading only).
    path = os.path.join(work_dir, "mujoco_model.mjb")
    mujoco.mj_saveModel(model, path)
    with open(os.path.join(work_dir, "mujoco_model_rounded.xml"), "w") as f:
        f.write(spec.to_xml())
    return path, order
