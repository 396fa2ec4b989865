/* lint.cl: a kernel family that builds with a warning, for tests/test_machine.py: falling off the end of
 * a non-void function is one of the few warnings clang shows by default. Not one of vmcl's kernels. */

int halve(int a)
{
    if (a > 0) return a / 2;
}

__kernel void k(__global int *x)
{
    x[0] = halve(x[0]);
}
