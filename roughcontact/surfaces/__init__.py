"""Stage 1, surfaces: the heights a contact cell is solved on.

Generated surfaces (Section 2 of Kumar et al. 2006): ``spec`` says what to
generate (``SurfaceSpec``); ``johnson`` fits Johnson's translator curves by
moments (Eq 6-8; their moments in ``johnson_moments``, the AS 99 and
bracketing solvers in ``johnson_solvers``); ``spectra`` holds the ACF of
Eq 1, the self-affine and tabulated PSDs and the linear filter built from
them (Eq 9-11); ``calibration`` the moment transfer of the filter and its
bound (Eq 12-15) and the calibration of a window's expected sample moments;
``synthetic`` the seeded generators (white noise -> Johnson translator ->
filter), ``exact`` the exact generator (IAAFT) and ``memory`` their memory
estimate; ``multiresolution`` resolves one band-limited surface on several
grids (grid-convergence studies). Measured surfaces: ``measured`` imports
and prepares a measured height map (``load_measurement``; formats in
``readers``, crop, holes, form and resampling in ``preparation``) and gives
its statistics. ``statistics``
holds the sample statistics of any height map (moments, ACF, correlation
lengths). Nothing here knows about the elastic body, the contact problem or
the workflow.
"""
