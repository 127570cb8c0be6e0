"""Parameter sweeps: a scene's quantities over a grid or a random sample of its parameters."""
