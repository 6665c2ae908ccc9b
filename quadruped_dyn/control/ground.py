"""The ground steps the plant accepts (``plant.PlantOptions.ground_step``), apart from the plant so that a sweep file's
ranges are checked against them without importing MuJoCo (``sweep.sampling``)."""

#: The largest ground step accepted, up or down (m): beyond, the legs' reach, not the controller, decides.
MAX_GROUND_STEP_M = 0.2
#: Half the length and width of a ground step's box (m), and the farthest its edge may be from the origin: past any
#: run's reach (100 cycles of the fastest gait).
GROUND_HALF_SIZE_M = 100.0
