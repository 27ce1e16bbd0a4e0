"""Physical constants [SI]."""

SPEED_OF_LIGHT_M_S: float = 299_792_458.0
"""Speed of light in vacuum [m/s] (exact, SI definition)."""
