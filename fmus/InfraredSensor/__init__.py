"""The InfraredSensor FMU: a fixed-wing in coordinated turns, its infrared horizon sensor and its GPS turn rate."""
