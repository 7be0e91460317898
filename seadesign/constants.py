"""Physical constants, each defined once."""

G_M_PER_S2 = 9.80665  # standard gravity (m/s^2)
