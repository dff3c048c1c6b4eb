"""External-wrench models of the vehicle: prescribed disturbances, gravity gradient."""
