// Sum over a workgroup with one barrier: subgroupAdd inside each subgroup, then invocation 0 adds
// the subgroups' sums in subgroup order (reproducible on a given device; no assumption on the
// subgroup size). The including shader enables GL_KHR_shader_subgroup_basic and _arithmetic and
// defines EVF_GROUP_SUM_SIZE (its workgroup size). Every invocation of the group must call it;
// the result is valid in invocation 0 only.
shared vec2 evf_group_partials[EVF_GROUP_SUM_SIZE];

vec2 evf_group_sum(vec2 v) {
  vec2 s = subgroupAdd(v);
  if (subgroupElect()) evf_group_partials[gl_SubgroupID] = s;
  barrier();
  vec2 total = vec2(0.0);
  if (gl_LocalInvocationIndex == 0u)
    for (uint i = 0u; i < gl_NumSubgroups; ++i) total += evf_group_partials[i];
  return total;
}
