"""pytest plugin of thruster-hil (placeholder; being written)."""
