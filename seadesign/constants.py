"""Physical constants and published figures, each defined once (SI units unless a name says
otherwise). Study and material files hold what a user may change; these are facts."""

G_M_PER_S2 = 9.80665  # standard gravity (CGPM 1901), m/s^2

# Stelter 2022 (the thesis), NASTRAN results for the candidates it reports numerically (fig. 5.3/5.4):
# (beam count, beam thickness mm) -> (peak reaction force N, stall bearing displacement mm)
THESIS_FEA_RESULTS = {(5, 6.0): (149.3, 0.6521), (9, 8.0): (150.3, 0.3532)}
THESIS_K_MEASURED_NM_PER_RAD = 9.106  # F/T-sensor bench test of the 9-beam 8 mm part (sec. 5.1)
THESIS_BEARING_RADIUS_M = 0.014  # where the FEA displacement was read (eq. 5.3)

# Wolfgang-OP humanoid and its Dynamixel XH540-W270 knee servo (thesis sec. 4.1, 5.1; data sheet)
WOLFGANG_MASS_KG = 8.0
WOLFGANG_LOWER_LEG_M = 0.2038
XH540_STALL_TORQUE_NM = 11.7
XH540_NO_LOAD_SPEED_RPM = 46.0
XH540_BACKLASH_DEG = 0.25

# ams AS5600 magnetic rotary encoder, the knee's deflection sensor (thesis sec. 5.2.1): 12-bit angle,
# 0-360 deg -> 4096 counts (ams AS5600 data sheet DS000365, "12-Bit Programmable Contactless Potentiometer")
AS5600_BITS = 12
