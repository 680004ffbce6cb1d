// Linear workgroup index for grids split over x and y (more than 65,535 groups).
uint evf_linear_group() { return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x; }
uint evf_linear_invocation(uint local_size) { return evf_linear_group() * local_size + gl_LocalInvocationIndex; }
