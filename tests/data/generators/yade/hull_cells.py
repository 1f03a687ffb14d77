#!/usr/bin/python3
"""The triangulation's hull cells on the tension runs (tension_runs.sh): how flat
the cracked cells near the bar's sides are, and how much of each method's main
crack lies there in faces that face across the pull axis (x).

    /usr/bin/python3 hull_cells.py RUN.h5 [CRACKVIS]     (Debian's python3-vtk9)

The bar is 80 x 30 x 30 mm, centred on the origin, pulled along x
(tension_bar.py); "near the sides" is a face or cell centre within 2 mm of
y = +-15 mm or z = +-15 mm, which holds the outer layer of centres. A cell's
quality is 6 sqrt(2) V / l_rms^3 (1 for a regular tetrahedron; a sliver, flat,
is under 0.1), of its nodes at the first step; the faces are the last step's.
"""
import os
import subprocess
import sys
import tempfile

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy

HALF_SIDE = 0.015  # the bar's half height and half width, m
BAND = 0.002       # "near the sides", m


def read(path):
    reader = vtk.vtkXMLPolyDataReader() if path.endswith(".vtp") else vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    return reader.GetOutput()


def near_sides(centres):
    return (np.abs(centres[:, 1]) > HALF_SIDE - BAND) | (np.abs(centres[:, 2]) > HALF_SIDE - BAND)


def cell_qualities(grid, reference):
    """Each cracked cell's quality and centre in the reference configuration
    (the first step, which the triangulation was made of): the last step's
    cells are stretched by the crack's opening."""
    ids = vtk_to_numpy(grid.GetPointData().GetArray("particle_id"))
    points = np.array([reference[int(i)] for i in ids])
    quality, centre = [], []
    for c in range(grid.GetNumberOfCells()):
        ids = grid.GetCell(c).GetPointIds()
        if ids.GetNumberOfIds() != 4:
            continue
        x = points[[ids.GetId(k) for k in range(4)]]
        volume = abs(np.linalg.det(np.array([x[1] - x[0], x[2] - x[0], x[3] - x[0]]))) / 6
        edges = [np.linalg.norm(x[a] - x[b]) for a in range(4) for b in range(a + 1, 4)]
        quality.append(6 * np.sqrt(2) * volume / np.sqrt(np.mean(np.square(edges))) ** 3)
        centre.append(x.mean(axis=0))
    return np.array(quality), np.array(centre)


def reference_positions(crackvis, run, out):
    """Particle id -> centre at the first step (`crackvis export`)."""
    path = os.path.join(out, "reference.pvd")
    subprocess.run([crackvis, "export", run, "--particles", "-s", "0", "-q", "-o", path], check=True,
                   stdout=subprocess.DEVNULL)
    particles = read(os.path.join(out, "reference", "reference_particles_000000.vtp"))
    ids = vtk_to_numpy(particles.GetPointData().GetArray("id"))
    centres = vtk_to_numpy(particles.GetPoints().GetData())
    return {int(i): centres[k] for k, i in enumerate(ids)}


def faces(poly):
    sizes = vtk.vtkCellSizeFilter()
    sizes.SetInputData(poly)
    sizes.Update()
    area = vtk_to_numpy(sizes.GetOutput().GetCellData().GetArray("Area"))
    centres = vtk.vtkCellCenters()
    centres.SetInputData(poly)
    centres.Update()
    normals = vtk.vtkPolyDataNormals()
    normals.SetInputData(poly)
    normals.ComputeCellNormalsOn()
    normals.ComputePointNormalsOff()
    normals.SplittingOff()
    normals.ConsistencyOff()
    normals.Update()
    along_x = np.abs(vtk_to_numpy(normals.GetOutput().GetCellData().GetNormals())[:, 0])
    bond = poly.GetCellData().GetArray("bond_id")
    virtual = vtk_to_numpy(bond) < 0 if bond is not None else None
    return area, vtk_to_numpy(centres.GetOutput().GetPoints().GetData()), along_x, virtual


def main():
    run = sys.argv[1]
    crackvis = sys.argv[2] if len(sys.argv) > 2 else "crackvis"
    with tempfile.TemporaryDirectory() as out:
        def extract(method, name, *extra):
            path = os.path.join(out, name)
            subprocess.run([crackvis, "extract", run, "-m", method, "-s", "-1", "-q", "-o", path, *extra],
                           check=True, stdout=subprocess.DEVNULL)
            return read(path)

        reference = reference_positions(crackvis, run, out)
        quality, centre = cell_qualities(extract("cell-attribute", "cells.vtu"), reference)
        side = near_sides(centre)
        for name, mask in (("near the sides", side), ("inside", ~side)):
            q = quality[mask]
            print(f"cracked cells {name:14s} {mask.sum():5d}: quality median {np.median(q):.2f}, "
                  f"slivers (q < 0.1) {np.mean(q < 0.1) * 100:4.1f} %")
        for method in ("local-voronoi", "cell-centre", "cell-cut"):
            area, centres, along_x, virtual = faces(extract(method, method + ".vtp", "--largest", "1"))
            side = near_sides(centres)
            across = along_x < 0.3
            share = lambda mask: area[mask].sum() / area.sum() * 100
            weighted = lambda mask: (area[mask] * along_x[mask]).sum() / area[mask].sum()
            line = (f"{method:13s} main crack: near the sides {share(side):4.1f} % of the area, mean |n.x| "
                    f"{weighted(side):.2f} there and {weighted(~side):.2f} inside; faces there with "
                    f"|n.x| < 0.3: {share(side & across):4.1f} %")
            if virtual is not None:
                line += f" (of virtual bonds {share(side & across & virtual):4.1f} %)"
            print(line)


if __name__ == "__main__":
    main()
