#!/usr/bin/env python3
"""Reads partlife .vtu files with VTK's own XML reader (pip install vtk) and checks the counts.

Usage: python3 tests/bench/check_vtu.py reports/crush_gen3_rt/*.vtu
Exit 0 and "ok" when every file reads; 1 on a rejected file; 3 when the vtk module is absent.
"""
import sys

try:
    import vtk
except ImportError:
    print("vtk module not installed")
    sys.exit(3)

for path in sys.argv[1:]:
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    n_arrays = g.GetCellData().GetNumberOfArrays()
    if g.GetNumberOfCells() == 0 or g.GetNumberOfPoints() == 0 or n_arrays < 9:
        print(f"{path}: rejected ({g.GetNumberOfPoints()} points, {g.GetNumberOfCells()} cells, {n_arrays} arrays)")
        sys.exit(1)
    for k in range(n_arrays):
        a = g.GetCellData().GetArray(k)
        if a.GetNumberOfTuples() != g.GetNumberOfCells():
            print(f"{path}: array {a.GetName()} has {a.GetNumberOfTuples()} values for {g.GetNumberOfCells()} cells")
            sys.exit(1)
    print(f"{path}: {g.GetNumberOfPoints()} points, {g.GetNumberOfCells()} quads, {n_arrays} cell arrays")
print("ok")
