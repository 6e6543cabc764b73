"""System identification of the arm (thesis §3.5)."""
