"""Index layout of the compiled model's flat arrays.

The compiled core (Numba) works on flat float64/int64 arrays; this module is the one place
that names their slots. Leg index 0 is the back virtual leg, 1 the front (docs/specification.md section 1:
back hip at -L, front hip at +L along the torso axis).

It is also the one table of the integer codes a run records (leg states ``LS_*``, contact
modes, motor-joint modes, model variants ``MODEL_*``, event kinds ``EK_*``, violation bits
``V_*``) and of their names (``*_NAMES``, ``MODEL_LABELS``): plain module-level ints, which
Numba reads as compile-time constants. :mod:`scoutsim.names` builds its enums from them.
"""

# fmt: off
# (a table: its columns and comments are aligned by hand)

# --- legs -------------------------------------------------------------------------------
BACK = 0
FRONT = 1
LEG_NAMES = ("back", "front")
HIP_SIGN = (-1.0, 1.0)  # hip position along the torso axis, in units of L

# --- state vector s = [q(7), dq(7), l_back, l_front] ----------------------------------------
# q = [x, y, theta, phi_b, phi_f, alpha_b, alpha_f]; alpha (Model II driven-gear angle
# relative to the torso) equals phi in the ideal / Model I / passive variants.
NQ = 7
IX, IY, ITH, IPHB, IPHF, IALB, IALF = range(7)
IL_B = 14
IL_F = 15
NS = 16
STATE_NAMES = (
    "x", "y", "theta", "phi_back", "phi_front", "alpha_back", "alpha_front",
    "dx", "dy", "dtheta", "dphi_back", "dphi_front", "dalpha_back", "dalpha_front",
    "leg_length_back", "leg_length_front",
)

# --- model variants -------------------------------------------------------------------
MODEL_IDEAL = 0
MODEL_I = 1
MODEL_II = 2
MODEL_PASSIVE = 3
MODEL_NAMES = {"ideal": MODEL_IDEAL, "I": MODEL_I, "II": MODEL_II, "passive": MODEL_PASSIVE}
#: display name of each model variant (tables, legends, titles)
MODEL_LABELS = {"ideal": "ideal actuator", "I": "Model I", "II": "Model II",
                "passive": "passive (no controller)"}

# --- contact modes (per leg) ------------------------------------------------------------
FLIGHT = 0
STICK = 1   # toe pinned at its anchor, spring/damper along the leg axis
SLIDE = 2   # toe on the ground sliding (frictionless or Coulomb)
STRUT = 3   # leg at its stop l0 with the toe pinned: rigid strut
CONTACT_NAMES = ("flight", "stick", "slide", "strut")

# --- constraint-row kinds (model/contact.py, model/kkt.py, model/impact.py) ---------------
# Each row of the constraint Jacobian R carries its kind and its leg; the kinds decide how a
# row's multiplier is read (ground force, strut force, holding torque) and which rows the
# reduced KKT solve eliminates (ROW_GEAR).
ROW_TOE_ACROSS = 1   # pinned toe: no toe velocity across the leg (spring leg or strut)
ROW_TOE_ALONG = 2    # strut: no toe velocity along the leg (leg length held at the stop)
ROW_GEAR = 3         # on the Model II gear angle: a stuck motor joint; the rigid belt of impact
ROW_MASSLESS = 4     # massless leg in flight: its angle is prescribed
ROW_CLAMP_TORSO = 5  # bench rig: torso x, y, theta held
ROW_CLAMP_LEG = 6    # bench rig: leg angle phi held

# --- motor-joint friction modes (Model II, per leg) -------------------------------------
SLIP_NEG = -1
STUCK = 0
SLIP_POS = 1
MOTOR_JOINT_NAMES = {SLIP_NEG: "slip_neg", STUCK: "stuck", SLIP_POS: "slip_pos"}

# --- integer mode array mi ------------------------------------------------------------
MI_CONTACT_B = 0
MI_CONTACT_F = 1
MI_MOTOR_B = 2
MI_MOTOR_F = 3
MI_SLIDE_DIR_B = 4
MI_SLIDE_DIR_F = 5
NMI = 6

# --- recorded modes (one row per sample: SimulationResult.modes, int8) --------------------
RM_LEG_STATE_B = 0   # controller leg state (LS_*), back
RM_LEG_STATE_F = 1
RM_CONTACT_B = 2     # plant contact mode (FLIGHT, STICK, SLIDE, STRUT), back
RM_CONTACT_F = 3
RM_MOTOR_B = 4       # motor-joint stiction mode (SLIP_NEG, STUCK, SLIP_POS), back
RM_MOTOR_F = 5
NRM = 6
RECORDED_MODE_NAMES = ("leg_state_back", "leg_state_front", "contact_mode_back",
                       "contact_mode_front", "motor_joint_mode_back", "motor_joint_mode_front")

# --- float mode array mf --------------------------------------------------------------
MF_ANCHOR_B = 0   # toe anchor x [m] while pinned
MF_ANCHOR_F = 1
NMF = 2

# --- parameter array P ----------------------------------------------------------------
# Whole-robot quantities take one slot each. Every leg, hip-unit and motor quantity takes
# two consecutive slots, back then front: P[P_X + leg] (leg = BACK, FRONT), so a robot
# whose legs differ is packed the same way as one whose legs are equal.
(P_MT, P_IT, P_L, P_COM_OFFSET, P_NP, P_G, P_TORSO_LEN, P_TORSO_H, P_VB, P_RB, P_MODEL,
 P_MU, P_MASSLESS, P_TD_WORLD, P_THETA_LIM, P_STRUT_OMEGA) = range(16)
# P_COM_OFFSET: the torso COM's distance ahead of the hips' midpoint [m] (0: midway)
# bench rigs (scoutsim.identification.rigs): clamps are extra constraint rows of
# the same KKT system; the motor circuit replaces the amplifier in an unpowered rig
P_CLAMP_TORSO = 16   # 1: torso x, y, theta held fixed (free swing, flight steps, stall)
P_CLAMP_LEGS = 17    # 1: leg angles phi held fixed relative to the torso (stall)
P_CIRCUIT = 18       # CIRCUIT_*: what drives the motor current
P_TD_B = 19          # passive massless legs: touchdown angle [rad], back
P_TD_F = 20          # and front
P_HIP_UNIT = 21      # the hip unit's code: its place in model/hip_unit.py's UNITS
P_NO_SLIP = 22       # 1: the toes cannot slip (friction_coefficient = inf; P_MU is then 0)
_FIRST_PER_LEG = 23
# per leg (P[P_X + leg]): leg body, telescopic leg, hip unit, motor and amplifier
(P_ML,         # mass of one physical leg body [kg]
 P_IL,         # its inertia about its COM [kg m^2]
 P_K,          # leg spring [N/m], per physical leg
 P_C,          # leg damper [N s/m], per physical leg
 P_L0,         # leg rest length = stop [m]
 P_D,          # hip to leg-body COM [m]
 P_N,          # gear ratio [-]
 P_ETA,        # transmission efficiency [-]
 P_J1,         # drive gear inertia [kg m^2]
 P_J2,         # driven gear inertia [kg m^2]
 P_TAU_S,      # motor-joint stiction [N m]
 P_B_J,        # motor-joint viscous friction [N m s/rad]
 P_KB,         # belt spring [N m/rad]
 P_CB,         # belt damper [N m s/rad]
 P_KT,         # torque constant [N m/A]
 P_KW,         # back-EMF constant [V s/rad]
 P_RA,         # armature resistance [ohm]
 P_IMAX,       # amplifier current limit [A]
 P_TAU_IDLE,   # torque-independent transmission loss [N m]
 P_C_LOAD,     # load-proportional transmission loss [-]
 # effects beyond the paper's models (RobotParameters docs; 0 = off)
 P_BACKLASH,   # total play of the belt spring's dead zone [rad]
 P_LEG_FRIC,   # Coulomb friction of the telescopic leg [N], per physical leg
 P_LEG_FRIC_SIDE,  # leg friction per unit side load |tau_hip| / l [-]
 P_LEG_C_ANGLE,    # leg damper factor (1 + a phi^2) [1/rad^2]
 ) = range(_FIRST_PER_LEG, _FIRST_PER_LEG + 2 * 24, 2)
NP_ = _FIRST_PER_LEG + 2 * 24

# --- motor circuit (P_CIRCUIT) -----------------------------------------------------------
CIRCUIT_AMPLIFIER = 0   # current amplifier with the limits of docs/specification.md section 4 (normal operation)
CIRCUIT_OPEN = 1        # motor leads open: no current, the gear train is back-driven freely
CIRCUIT_SHORT = 2       # motor leads shorted: i = -K_w w_m / R_A (back-EMF braking)
CIRCUIT_NAMES = {"amplifier": CIRCUIT_AMPLIFIER, "open": CIRCUIT_OPEN, "short": CIRCUIT_SHORT}

# --- auxiliary outputs (per evaluation) ---------------------------------------------------
# per leg (offset leg * NAUX_LEG)
A_GT = 0         # ground tangential force on the toe [N] (virtual leg)
A_GN = 1         # ground normal force [N]
A_FAX = 2        # axial leg force, compression positive [N] (virtual leg)
A_TAU_CMD = 3    # commanded hip torque, per physical leg, leg side [N m]
A_TAU_APP = 4    # applied actuator torque, per physical leg, leg/driven-gear side [N m]
A_CURRENT = 5    # motor current, per motor [A]
A_OMEGA_M = 6    # motor speed relative to the torso [rad/s]
A_BELT = 7       # belt deflection alpha - phi [rad]
A_HOLD = 8       # stiction holding torque at the motor while stuck, per motor [N m]
A_TOE_X = 9
A_TOE_Y = 10
A_SLIP_V = 11    # toe horizontal velocity [m/s]
A_STRUT = 12     # strut axial multiplier (tension positive) [N]
A_TAU_BELT = 13  # belt torque on the leg, per physical leg [N m]
NAUX_LEG = 14
A_VBATT = 2 * NAUX_LEG      # battery voltage [V]
A_ENERGY = A_VBATT + 1      # total mechanical energy [J]
A_KKT_OK = A_ENERGY + 1     # 1 if the constrained dynamics solved, 0 if singular
NAUX = A_KKT_OK + 1
AUX_LEG_NAMES = ("ground_force_tangential", "ground_force_normal", "leg_axial_force",
                 "hip_torque_commanded", "hip_torque_applied", "motor_current",
                 "motor_speed", "belt_deflection", "stiction_holding_torque", "toe_x",
                 "toe_y", "toe_velocity_x", "strut_force", "belt_torque")

# --- work-energy balance (simulate(energy=True); SimulationResult.energy_balance) -------
# Energies [J] accumulated over a run by integrating each power flow on every integrator
# step (model/power_flows.py). Per virtual leg (offset leg * NEN_LEG; both motors of the leg):
EN_ELECTRICAL = 0      # electrical energy into the motor terminals, i (R_A i + K_w w_m)
EN_COPPER = 1          # armature copper losses R_A i^2
EN_CONVERSION = 2      # the paper's constant-efficiency loss (K_w - eta K_T) i w_m (signed:
                       # negative while a leg back-drives its motor)
EN_GEAR_LOSS = 3       # the optional load-dependent transmission loss (tau_0 - tau_out) w_m / N
EN_HIP_WORK = 4        # work of the delivered hip torque on the leg (Model II: driven gear)
EN_JOINT_VISCOUS = 5   # motor-joint viscous friction b_J w_m^2 (Model II)
EN_JOINT_COULOMB = 6   # motor-joint Coulomb (stiction level) friction while slipping (Model II)
EN_BELT_DAMPER = 7     # belt damper c_b (alpha' - phi')^2 (Model II)
EN_LEG_DAMPER = 8      # telescopic leg damper c (1 + a phi^2) l'^2
EN_LEG_FRICTION = 9    # telescopic leg sliding-joint friction
EN_TOE_SLIDE = 10      # friction of a sliding toe on the floor, -F_t v_toe
EN_CONSTRAINT = 11     # work of the constraint forces (zero up to the drift the Baumgarte
                       # terms of a rigid strut correct; kept as a term, not hidden)
NEN_LEG = 12
EN_BATTERY_LOSS = 2 * NEN_LEG   # the battery's internal resistance R_b I_b^2
NEN = EN_BATTERY_LOSS + 1
EN_LEG_NAMES = ("electrical", "copper", "conversion", "gear_loss", "hip_work",
                "joint_viscous", "joint_coulomb", "belt_damper", "leg_damper",
                "leg_friction", "toe_slide", "constraint")

# --- touchdown impact outputs (model/impact.py) ------------------------------------------
# per leg (offset leg * NIMP_LEG): the impulse on each pinned toe [N s]
IMP_NORMAL = 0        # ground normal impulse
IMP_TANGENT = 1       # ground tangential impulse
NIMP_LEG = 2
IMP_ENERGY_LOST = 2 * NIMP_LEG   # kinetic energy lost in the impact [J]
NIMP = IMP_ENERGY_LOST + 1

# --- events ---------------------------------------------------------------------------
# slots: per leg 3 contact slots, per leg 1 motor slot, 2 fall slots
NEV_CONTACT = 3
# the contact slots of a leg (offset leg * NEV_CONTACT; numerics/events.py), by contact mode:
EVC_GROUND = 0         # flight: toe height (touchdown); stick, slide, strut: ground normal
                       # force (lift-off, or a slide if the leg still pushes)
EVC_STOP_OR_REST = 1   # stick: leg length at its stop (-> strut); slide: toe velocity along
                       # its slide direction (-> stick, Coulomb floor); strut: strut force
                       # (-> stick)
EVC_CONE = 2           # stick on a Coulomb floor: friction force within mu F_n (-> slide);
                       # slide on a Coulomb floor: the sliding ground force's share along
                       # the leg above its jam level (-> jam: the toe sticks with an impact)
EV_MOTOR_B = 6
EV_MOTOR_F = 7
EV_FALL_HEIGHT = 8
EV_FALL_PITCH = 9
NEV = 10

# event kinds written to the event log
EK_TOUCHDOWN = 1
EK_LIFTOFF = 2
EK_SLIDE_START = 3     # toe starts to slide (v3: SLIDE_CAUSE_*)
EK_STICK = 4           # sliding toe sticks again
EK_STRUT_START = 5
EK_STRUT_END = 6
EK_MOTOR_STICK = 7
EK_MOTOR_SLIP = 8
EK_FALL = 9
# v3 of a slide_start record: why the toe slides
SLIDE_CAUSE_LEG_PUSHES = 0      # a pinned toe the ground would pull while the leg still pushes
SLIDE_CAUSE_CONE = 1            # the friction force reached mu F_n (Coulomb floor)
SLIDE_CAUSE_NO_PIN_IMPULSE = 2  # touchdown whose pinning impulse the floor cannot give
SLIDE_CAUSE_STUB = 3            # a leg at its stop whose toe is pressed into the ground
EK_CTRL_TOUCHDOWN = 10   # controller detects touchdown
EK_CTRL_LIFTOFF = 11     # controller detects lift-off
EK_CTRL_SWEEP = 12       # controller passes the sweep limit
EK_JAM = 13              # a sliding toe jams: stopped by an impact without collision
EVENT_KIND_NAMES = {
    EK_TOUCHDOWN: "touchdown", EK_LIFTOFF: "liftoff", EK_SLIDE_START: "slide_start",
    EK_STICK: "stick", EK_STRUT_START: "strut_start", EK_STRUT_END: "strut_end",
    EK_MOTOR_STICK: "motor_stick", EK_MOTOR_SLIP: "motor_slip", EK_FALL: "fall",
    EK_CTRL_TOUCHDOWN: "controller_touchdown", EK_CTRL_LIFTOFF: "controller_liftoff",
    EK_CTRL_SWEEP: "controller_sweep_limit", EK_JAM: "jam",
}
#: event kinds whose record is an impact: v1, v2 its normal and tangential impulse [N s],
#: v3 the kinetic energy it dissipated [J] (touchdowns, and the jams of sliding toes)
IMPACT_KINDS = (EK_TOUCHDOWN, EK_JAM)
# event record: [t, kind, leg, v1, v2, v3, energy_before, energy_after, violations]
# touchdown, jam: v1 = normal impulse [N s], v2 = tangential impulse, v3 = kinetic energy lost [J]
# Transition audit (every plant transition, numerics/events.py): the records logged while one
# transition is processed (an event, the events simultaneous with it and the mode changes
# they cause) carry the total mechanical energy [J] just before it and after the modes have
# settled, and a bit mask of the mode invariants violated after it (V_* below; 0 = none).
# Controller records carry NaN energies (they are not plant transitions).
EVR_T = 0
EVR_KIND = 1
EVR_LEG = 2
EVR_V1 = 3
EVR_V2 = 4
EVR_V3 = 5
EVR_E_BEFORE = 6
EVR_E_AFTER = 7
EVR_VIOLATIONS = 8
NEVREC = 9
# The run's event buffer carries, after those NEVREC columns, the exact state of every
# plant transition (layout STATE_NAMES): just before it (at the located event time, before
# impacts and mode changes) and after its modes have settled; controller records carry the
# state at their sample (before = after). ``SimulationResult.event_states`` holds them as
# (m, 2, NS): [:, EVS_BEFORE] and [:, EVS_AFTER].
EVR_STATE_BEFORE = NEVREC
EVR_STATE_AFTER = NEVREC + NS
NEVBUF = NEVREC + 2 * NS
EVS_BEFORE = 0
EVS_AFTER = 1

# --- integrator step records (simulate(record_steps=True), SimulationResult.steps) --------
# One row per step of the integrator (accepted steps and the steps cut at located events):
# the time [s] and state at its end and the plant modes during it.
STP_T = 0
STP_STATE = 1                      # .. STP_STATE + NS - 1, layout STATE_NAMES
STP_CONTACT_B = 1 + NS             # contact mode of the back / front toe (CONTACT_NAMES)
STP_MOTOR_B = 3 + NS               # motor-joint mode of the back / front leg (Model II)
NSTEPREC = 5 + NS

# --- transition invariants (bits of EVR_VIOLATIONS), checked after every transition -------
V_GROUND_PULLS = 1        # a pinned toe or strut whose ground normal force pulls
V_OUTSIDE_CONE = 2        # a pinned toe (Coulomb floor) needing more than mu |F_n|
V_SLIDE_DIRECTION = 4     # a sliding toe moving against its recorded slide direction
V_SLIDE_NOT_PUSHING = 8   # a sliding toe whose leg no longer pushes
V_TOE_BELOW_GROUND = 16   # a toe in flight below the ground
V_STICTION_EXCEEDED = 32  # a stuck motor joint held by more than its stiction
V_SLIP_DIRECTION = 64     # a slipping motor joint moving against its slip direction
V_STRUT_COMPRESSED = 128  # a rigid strut in compression (should be a spring leg again)
V_SINGULAR = 256          # the constrained dynamics could not be solved
V_BEYOND_STOP = 512       # a spring leg with its pinned toe extended beyond the stop l0
V_TOE_ENTERS_GROUND = 1024  # a toe in flight at ground level moving or accelerating into it
VIOLATION_NAMES = {
    V_GROUND_PULLS: "ground pulls a pinned toe", V_OUTSIDE_CONE: "pinned toe outside the "
    "friction cone", V_SLIDE_DIRECTION: "toe slides against its slide direction",
    V_SLIDE_NOT_PUSHING: "sliding leg does not push", V_TOE_BELOW_GROUND: "toe in flight below "
    "the ground", V_STICTION_EXCEEDED: "stuck motor joint beyond breakaway",
    V_SLIP_DIRECTION: "motor joint slips against its slip direction",
    V_STRUT_COMPRESSED: "strut in compression", V_SINGULAR: "constrained dynamics singular",
    V_BEYOND_STOP: "pinned leg extended beyond its stop",
    V_TOE_ENTERS_GROUND: "toe in flight at the ground moving into it",
}

# --- sensor readings (model/sensor_readings.py -> the controller) -------------------------------
# The robot's sensors at a control sample, one slot per reading (SI units); the leg
# channels in back, front order. ``scoutsim.control.sensors.Sensors`` names them for
# Python controllers; compiled controllers read these slots.
SN_ANGLE_B = 0    # hip encoder: hip angle relative to the torso [rad] (motor side in
SN_ANGLE_F = 1    #   Model II when the controller senses the motor angle), back, front
SN_RATE_B = 2     # hip rate [rad/s], back, front
SN_RATE_F = 3
SN_LENGTH_B = 4   # leg length (linear potentiometer) [m], back, front
SN_LENGTH_F = 5
SN_PITCH = 6      # IMU: torso pitch [rad], nose up positive
SN_PITCH_RATE = 7 # IMU: torso pitch rate [rad/s]
SN_ACCEL_X = 8    # IMU accelerometer at the torso COM, specific force along the torso axis
SN_ACCEL_Z = 9    #   (forward) and along its normal (up) [m/s^2]: reads +g at rest
SN_RANGE_B = 10   # torso laser range finders at the torso's back / front end [m]
SN_RANGE_F = 11
SN_CURRENT_B = 12 # motor current [A], per motor, back / front
SN_CURRENT_F = 13
SN_BATTERY = 14   # battery (motor supply) voltage [V]
NSN = 15
#: the sensor channels: (name, first slot, number of slots, SI unit)
SENSOR_CHANNELS = (
    ("hip_angle", SN_ANGLE_B, 2, "rad"), ("hip_rate", SN_RATE_B, 2, "rad/s"),
    ("leg_length", SN_LENGTH_B, 2, "m"), ("pitch", SN_PITCH, 1, "rad"),
    ("pitch_rate", SN_PITCH_RATE, 1, "rad/s"), ("acceleration", SN_ACCEL_X, 2, "m/s^2"),
    ("laser_range", SN_RANGE_B, 2, "m"), ("motor_current", SN_CURRENT_B, 2, "A"),
    ("battery_voltage", SN_BATTERY, 1, "V"),
)
# measurement model of each slot (rows of the sensor specification array, NSPEC x NSN)
SPEC_NOISE = 0        # standard deviation of white Gaussian noise [slot unit]
SPEC_BIAS = 1         # constant offset [slot unit]
SPEC_RESOLUTION = 2   # quantization step [slot unit] (0 = continuous)
SPEC_DELAY = 3        # delay [control periods] (whole number)
NSPEC = 4
#: longest delay a sensor may have [control periods]
MAX_SENSOR_DELAY = 100
# geometry and flags of the sensors (the sensor geometry array)
SG_LASER_HALF_SPACING = 0   # laser range finders' distance from the torso COM [m]
SG_LASER_MOUNT_OFFSET = 1   # their aperture below the torso axis [m]
SG_MOTOR_SIDE = 2           # 1: hip encoders read the motor side (Model II alpha)
SG_MEASURED = 3             # 1: some channel has noise, bias, resolution or delay
NSG = 4

# --- controllers run by the compiled loop (control/dispatch.py) -------------------------
CTRL_BUILTIN = 0    # the Table I law (control/bounding.py), compiled in
CTRL_POINTER = 1    # a compiled function called through its address (a CompiledController,
                    # or the bridge that calls a Python controller)
CTRL_HELD = 2       # no controller: the commands are held as set (bench rigs)
# the control block's integers
CB_KIND = 0         # CTRL_*
CB_ADDRESS = 1      # address of the controller function (CTRL_POINTER)
CB_SEED = 2         # seed of the sensor noise
CB_STATUS = 3       # what a controller function returned when it stopped the run
NCB = 4

# --- controller leg states ------------------------------------------------------------
LS_FLIGHT = 0
LS_RETRACTION = 1
LS_BRAKE = 2
LEG_STATE_NAMES = ("flight", "stance-retraction", "stance-brake")
# bits of the controller's per-leg transition mask (control/bounding.py): what one sample
# of the Table I law detected; the run loop logs each as an EK_CTRL_* event
TR_TOUCHDOWN = 1   # flight -> stance-retraction (leg compression beyond the threshold)
TR_SWEEP = 2       # stance-retraction -> stance-brake (hip angle below the sweep limit)
TR_LIFTOFF = 4     # stance -> flight (compression below the lift-off threshold)

# --- run status -----------------------------------------------------------------------
ST_RUNNING = 0
ST_COMPLETED = 1
ST_FELL = 2
ST_NUMERICAL_FAILURE = 3
ST_CONTROLLER_ERROR = 4   # the controller raised or returned no finite torques
STATUS_NAMES = {ST_RUNNING: "running", ST_COMPLETED: "completed", ST_FELL: "fell",
                ST_NUMERICAL_FAILURE: "numerical_failure",
                ST_CONTROLLER_ERROR: "controller_error"}
# fmt: on
