"""Robot models by name (Pinocchio), each carrying a tool frame."""
