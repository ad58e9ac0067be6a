"""File writers and readers (STEP, STL, 3MF, OBJ, PLY, glTF) built on splinekit.

Nothing is here yet; the exporters issue fills this package.
"""
