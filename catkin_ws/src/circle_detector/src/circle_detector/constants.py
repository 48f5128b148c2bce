"""Every constant of the circle detector in one place (defaults of the original node's parameters)."""

DEFAULT_TF_PREFIX = "mbzirc2020_1"
DEFAULT_DP = 1.0
DEFAULT_MIN_DIST_BETWEEN_CIRCLE_CENTER = 480 // 8  # pixels at full resolution
DEFAULT_CANNY_EDGE_UPPER_THRESHOLD = 150.0
DEFAULT_ACCUMULATOR_THRESHOLD = 50              # votes at full resolution
DEFAULT_MIN_RADIUS = 0                          # pixels at full resolution, 0 = no bound
DEFAULT_MAX_RADIUS = 0
DEFAULT_MIN_RADIUS_METERS = 0.05
DEFAULT_MAX_RADIUS_METERS = 0.6
DEFAULT_MAX_DEPTH_TH = 10.0                     # metres
DEFAULT_USE_GAUSSIAN_BLUR = False
DEFAULT_GAUSSIAN_BLUR_SIGMA = 2.0
DEFAULT_GAUSSIAN_BLUR_KERNEL_SIZE = 3
# Extension of this port: Hough runs on the image shrunk by this factor (pixel parameters are scaled
# with it), which is what makes 640x480 run at >= 30 frames/s on one core; 1 = the original.
DEFAULT_DOWNSCALE = 2
# Extension: warp the image to face the facade plane fitted to the depth before Hough (circles seen up
# to 40 degrees off the normal are ellipses that HoughCircles misses); False = the original.
DEFAULT_RECTIFY = True

DEPTH_SCALE_16UC1 = 0.001  # 16UC1 depth is in millimetres; 0 means no data
# Where the depth of a circle is read: the annulus between these fractions of its radius (the rim on the
# facade), because the centre pixel of a real hole looks through it or has no data.
RIM_INNER = 1.05
RIM_OUTER = 1.35
RIM_MIN_VALID = 5  # depth pixels needed in the annulus
# Extension: is a circle an opening (the hole, with the fire's container behind) or painted (a decoy)? The
# depth of the middle of the disc (within INSIDE_RADIUS of its radius) is compared with the rim's.
INSIDE_RADIUS = 0.5
INSIDE_MIN_VALID = 3       # depth pixels needed in the middle
OPENING_MIN_DEPTH = 0.1    # m behind the rim for a circle to count as an opening (the container: ~0.3 m)

# Choosing the hole to shoot among circles on one facade holder (hole in the middle, decoys each side):
TRIPLE_MAX_RADIUS_RATIO = 1.6     # largest/smallest radius of the three
TRIPLE_MAX_SPACING_RATIO = 1.6    # larger/smaller gap between neighbours
TRIPLE_MAX_VERTICAL_SLOPE = 0.35  # vertical spread / horizontal extent
TRIPLE_MAX_DEPTH_SLOPE = 1.2      # depth spread / horizontal spread (a facade turned up to ~50 degrees)
TRIPLE_MAX_GAP_IN_RADII = 8.0     # neighbour gap / mean radius
