"""Shader node groups that sample pre-filtered colour-map lookups.

- "Penumbra Filtered Ramp" (one per lookup image): Mean, Sigma -> Color,
  Alpha. Maps (mean, σ) to the lookup's texel centres and interpolates it
  bilinearly from four Image Texture nodes set to Closest / EXTEND (no
  mipmaps, no wrap at the edges).
- "Penumbra Pixel Footprint": Pixel Size, Orthographic, Raster Offset X/Y
  -> Footprint, Minor, Major, Axis U, Axis V, Centre Offset: the pixel's
  footprint on the surface from the Jacobian of the camera projection, and
  the offset to the pixel's centre (see docs/colormap.md, "Footprint").
- "Penumbra Point Footprint": Pixel Size, Orthographic -> Footprint,
  Minor, Major: the footprint's axes from the view depth and slant alone,
  for the one-evaluation filter (point_footprint.py).
- "Penumbra Noise Filter" (per noise setting): Vector, Scale, Units per
  World, Minor, Major, Axis U, Axis V, Samples, W -> Mean, Sigma, Offsets,
  Variances, the octave-wise filter of the noise with 16 taps (8 or 4 in
  EEVEE for costly noises) over the sample's share of the footprint, as one
  Gaussian (Mean, Sigma) and as a mixture of four (Offsets, Variances).
- "Penumbra Height Filtered Ramp" / "Penumbra Slope Filtered Ramp": paper
  Sec. 5.1 / 5.2, reading the microsurface statistics image.
Each group is built by its own module (filtered_ramp.py, footprint.py, point_footprint.py,
noise_filter.py, height_ramp.py, slope_ramp.py; the microsurface table by
microsurface.py) with node_builder.py, so the same code makes them in
Blender 3.4 (inputs/outputs) and 4.x (interface). Here are their names: a
contract, since .blend files hold groups by these names."""

FILTERED_RAMP = "Penumbra Filtered Ramp"
FOOTPRINT = "Penumbra Pixel Footprint"
POINT_FOOTPRINT = "Penumbra Point Footprint"
NOISE_FILTER = "Penumbra Noise Filter"
HEIGHT_RAMP = "Penumbra Height Filtered Ramp"
SLOPE_RAMP = "Penumbra Slope Filtered Ramp"
MICROSURFACE_IMAGE = "Penumbra Microsurface Statistics"
