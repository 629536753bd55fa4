"""robodiff's checks evaluate the very libraries robodiff bench timed: `robodiff compute
--backend generated --kept WORK/robodiff_bench/ROW` loads the library bench kept for ROW
when it is the one the spec builds (same normalised spec, same generated C; compute
refuses it otherwise), so nothing is compiled again for the checks."""
import os


def command(robodiff, robot, spec, work, row, state_path):
    """The compute command line of `spec` at the state in `state_path`, on bench's kept ROW."""
    cmd = [robodiff, "compute", "--urdf", robot.urdf, "--spec", spec, "--backend", "generated",
           "--kept", os.path.join(work, "robodiff_bench", row), "--state", state_path]
    return cmd + (["--floating-base"] if robot.floating_base else [])
