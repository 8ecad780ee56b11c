"""The course's exercises, solved: the teacher's reference solutions, one module per task.

Each module is what a student hands in, filled: self-contained (the standard library and numpy
only), one graded function with its docstring (what it computes, its inputs and outputs, the
lecture's formula) and a small example.  `shadowvol course new DIR` writes these modules with
every function body replaced by `raise NotImplementedError` (`shadowvol.course.workspace`);
`shadowvol course solutions DIR` writes them as they are.  The grader
(`shadowvol.course.grader`) never calls them: it checks a student's functions against the
project's own implementation (the ray tracer's intersections, the rasterizer's silhouettes, the
2D exercise), and the tests check these solutions against the same witness.
"""
