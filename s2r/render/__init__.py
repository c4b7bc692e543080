"""PyBullet camera simulation: boards and ground-truth depth scenes (the only pybullet importer)."""
