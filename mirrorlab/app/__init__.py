"""Interactive front ends (glfw windows)."""
