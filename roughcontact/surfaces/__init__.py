"""Stage 1, surfaces: the heights a contact cell is solved on.

``johnson`` fits Johnson's translator curves by moments (Section 2.1 of Kumar
et al. 2006); ``synthetic`` generates seeded random surfaces (white noise ->
Johnson translator -> linear filter from the ACF, Eq 1-13, or the exact
generator); ``measured`` imports and prepares measured height maps. Nothing
here knows about the elastic body, the contact problem or the workflow.
"""
