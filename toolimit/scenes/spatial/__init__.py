"""3D scenes: batched, vectorised numpy worlds with Pinocchio/coal geometry."""
