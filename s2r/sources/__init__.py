"""Robot descriptions (URDF, xacro, SDF) to sim profiles, lint, and export back to Gazebo."""
