"""Every fixed ceiling of softevo in one place, read by every layer: run configs, robot files,
the service's settings and its defaults. (Operators lower the service's own ceilings with
`SOFTEVO_*` variables: `softevo.api.settings.Limits`; these are the bounds around them.)"""

from __future__ import annotations

#: Largest bounding-box side and voxel count of any robot, evolved or read from a file.
MAX_SIDE = 32
MAX_VOXELS = 4096
#: Largest robot file read (bytes).
MAX_FILE_BYTES = 8 * 1024 * 1024
#: The service's default ceiling on one run's voxels (SOFTEVO_MAX_VOXELS; at most MAX_VOXELS):
#: a 10x10x10 box, what the `cppn` encoding grows bodies in (512, an 8x8x8 box, until issue 38);
#: what a run may simulate in it is bounded by the cost budget (`softevo.api.cost`).
SERVICE_MAX_VOXELS = 1000
#: Robots per evaluator call in the service by default (SOFTEVO_BATCH_SIZE); the local pool cuts
#: no chunk smaller than this.
BATCH_SIZE = 4
#: Lattice points of the largest box the kernels count as small (the paper's cube has 8, a 2x2x2
#: box 27): a call of few such robots costs more than their simulation, so a run sends
#: them `SMALL_BATCH` at a time (a full AVX-512 vector of lanes: a paper-cube robot took 3.9 ms in
#: a call of 8 against 5.9 ms in one of 4, BENCHMARKS.md "Small robots"), and the physics runs
#: fewer than 4 of them robot by robot.
SMALL_POINTS = 27
SMALL_BATCH = 8
#: Batches of one run in flight at once by default (SOFTEVO_QUEUED_BATCHES in the service).
IN_FLIGHT = 64
#: The service saves a batch's fitness as it lands unless the run was written less than this
#: long ago (s; SOFTEVO_SAVE_SECONDS): then it waits for the next write, at most this long. So
#: quick generations cost one transaction, and a crash loses at most about this much finished
#: evaluation per run (besides the batches in flight).
SAVE_SECONDS = 1.0
#: Most mass positions one replay carries (frames x masses), about 20 MB of JSON.
MAX_REPLAY_POSITIONS = 1_000_000
#: Most cells of a quality-diversity archive (the product of its `bins`) and most descriptors.
MAX_ARCHIVE_CELLS = 10_000
MAX_DESCRIPTORS = 3
#: Most settings in a strategy's own `options` (each validated by the strategy's model).
MAX_OPTIONS = 64
#: Shortest length of a terrain feature (m): a step's tread, a bar and the space between bars,
#: a rough field's wavelength. A twentieth of the default voxel edge: finer, the features are
#: far below what a robot's masses (one per voxel corner) can meet, and a drawn mesh or a
#: cosine's argument grows without bound (a wavelength of 1e-300 m made every robot NaN).
MIN_TERRAIN_LENGTH = 0.05
#: Fewest and most frames per simulated second, most simulated seconds, of one moving picture.
MIN_PICTURE_FPS = 0.5
MAX_PICTURE_FPS = 30.0
MAX_PICTURE_SECONDS = 20.0
#: The service's tighter bounds on a picture rendered on a GET (/runs/{id}/best/replay.gif).
SERVICE_PICTURE_FPS = 15.0
SERVICE_PICTURE_SECONDS = 6.0
