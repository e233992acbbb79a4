"""Actions for the MuJoCo drop example (see ../README.md)."""
