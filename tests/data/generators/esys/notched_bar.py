# notched_bar.py -- ESyS-Particle 2.3.5 (Debian 12 package) script: tension
# test of a notched, bonded, polydisperse 3D bar.  Produces test data for
# crackvis's ESyS importer.  Run it through run.sh, which does
#     mpirun -np 2 esysparticle notched_bar.py
# (1 master + 1 worker process) in a scratch directory.
#
# Geometry (arbitrary length unit):
#   bar    random packing of RotSpheres, radii RMIN..RMAX, in the box
#          x in [0, LX], y in [0, LY], z in [0, LZ]
#   notch  at x = LX/2 from the top face (y = LY) down to y = LY - NOTCH_DEPTH,
#          through the whole z range: particles whose centre lies within
#          NOTCH_HW of the plane x = LX/2 above the notch tip are removed, and
#          bonds that cross that plane above the notch tip are not created.
#   tags   2 = left grip (centre x < GRIP), 3 = right grip
#          (centre x > LX - GRIP), 1 = everything else.
#   bonds  ConnectionFinder (touching particles) -> BrittleBeamPrms group
#          "pp_bonds" (bond tag 1); snapshots list it as "RotBonded".
# Loading: the grip particles are non-dynamic and are moved apart along x with
# moveTaggedParticlesBy (speed ramped from 0 to V_PULL per grip over RAMP
# steps, applied every MOVE_EVERY steps).  Strong viscous damping keeps the
# crack growth slow, so it spreads over several snapshots before the ligament
# under the notch has broken through and the bar is in two pieces.
from __future__ import division, print_function

from esys.lsm import *
from esys.lsm.util import *
from esys.lsm.geometry import *

SEED = 3                  # seedDefaultRng: makes RandomBoxPacker repeatable

LX, LY, LZ = 5.0, 3.8, 3.8
RMIN, RMAX = 0.2, 0.5
NOTCH_HW = 0.15           # half-width of the particle-free slot (x)
NOTCH_DEPTH = 0.4 * LY    # notch depth from the top face (y)
MAXDIST = 0.01 * RMIN     # ConnectionFinder gap tolerance
GRIP = 0.8                # grip zone length at each end

BOND_TAG = 1
TAG_BULK, TAG_LEFT, TAG_RIGHT = 1, 2, 3

DT = 2.0e-4
NSTEPS = 7000
SNAP_INCR = 700           # snapshots + bond count at t = 0, 700, ..., 7000
LOAD_INCR = 100           # grip force / displacement record
V_PULL = 0.01             # grip speed (each grip, opposite directions)
RAMP = 2000               # steps over which the grip speed is ramped up
MOVE_EVERY = 4            # the grips are moved every MOVE_EVERY steps
VISC = 50.0               # LinDamping / RotDamping viscosity

# --- simulation object: one worker process --------------------------------
sim = LsmMpi(numWorkerProcesses=1, mpiDimList=[1, 1, 1])
sim.initNeighbourSearch(particleType="RotSphere", gridSpacing=2.5 * RMAX,
                        verletDist=0.2 * RMIN)
sim.setNumTimeSteps(NSTEPS)
sim.setTimeStepSize(DT)
sim.setSpatialDomain(BoundingBox(Vec3(-5.0, -5.0, -5.0),
                                 Vec3(LX + 5.0, LY + 5.0, LZ + 5.0)))

# --- random polydisperse packing ------------------------------------------
seedDefaultRng(SEED)
packer = RandomBoxPacker(
    minRadius=RMIN, maxRadius=RMAX, cubicPackRadius=1.1 * RMAX,
    maxInsertFails=2000,
    bBox=BoundingBox(Vec3(0.0, 0.0, 0.0), Vec3(LX, LY, LZ)),
    circDimList=[False, False, False], tolerance=1.0e-5)
packer.generate()
packing = packer.getSimpleSphereCollection()

xmid = 0.5 * LX
ytip = LY - NOTCH_DEPTH
kept = []
centre = {}
ntag = {TAG_BULK: 0, TAG_LEFT: 0, TAG_RIGHT: 0}
for s in packing:
    c = s.getCentre()
    if abs(c[0] - xmid) < NOTCH_HW and c[1] > ytip:
        continue                      # centre inside the notch slot
    if c[0] < GRIP:
        tag = TAG_LEFT
    elif c[0] > LX - GRIP:
        tag = TAG_RIGHT
    else:
        tag = TAG_BULK
    s.setTag(tag)
    ntag[tag] += 1
    kept.append(s)
    centre[s.getId()] = (c[0], c[1], c[2])

print("packed %d spheres, kept %d after cutting the notch (tag counts %s)"
      % (packing.getNumSpheres(), len(kept), sorted(ntag.items())))
sim.createParticles(kept)

# --- bonds between touching particles (ids are the packer ids) ------------
# Keep the finder referenced while iterating over it: its iterator does not
# own it (a temporary finder made the run hang).
finder = ConnectionFinder(maxDist=MAXDIST, bondTag=BOND_TAG, pList=kept)
bonds = []
skipped = 0
for b in finder:
    p1, p2 = centre[b.getId1()], centre[b.getId2()]
    crosses = (p1[0] - xmid) * (p2[0] - xmid) < 0.0
    if crosses and 0.5 * (p1[1] + p2[1]) > ytip:
        skipped += 1                  # no bonds across the notch
        continue
    bonds.append(b)
print("created %d bonds (%d across the notch left out)" % (len(bonds), skipped))
sim.createConnections(bonds)

sim.createInteractionGroup(BrittleBeamPrms(
    name="pp_bonds", youngsModulus=1.0e4, poissonsRatio=0.25,
    cohesion=50.0, tanAngle=1.0, tag=BOND_TAG))

# contact between unbonded particles (e.g. across the crack)
sim.createInteractionGroup(FrictionPrms(
    name="friction", youngsModulus=1.0e4, poissonsRatio=0.25,
    dynamicMu=0.4, staticMu=0.6))
sim.createExclusion(interactionName1="pp_bonds", interactionName2="friction")

sim.createInteractionGroup(LinDampingPrms(
    name="damping_lin", viscosity=VISC, maxIterations=50))
sim.createInteractionGroup(RotDampingPrms(
    name="damping_rot", viscosity=VISC, maxIterations=50))

# --- grips -----------------------------------------------------------------
# (non-dynamic particles ignore setTaggedParticleVelocity, so they are moved
# explicitly)
sim.setParticleNonDynamic(TAG_LEFT)
sim.setParticleNonDynamic(TAG_RIGHT)


class GripLoader(Runnable):
    """Move the grips apart; speed ramps from 0 to V_PULL over RAMP steps."""

    def __init__(self, lsm):
        Runnable.__init__(self)
        self.sim = lsm
        self.n = 0
        self.acc = 0.0

    def run(self):
        # displacement accumulated over MOVE_EVERY steps is applied at once
        # (fewer master->worker commands; the increments are tiny anyway)
        self.acc += V_PULL * min(1.0, float(self.n) / float(RAMP)) * DT
        self.n += 1
        if self.n % MOVE_EVERY == 0 and self.acc > 0.0:
            self.sim.moveTaggedParticlesBy(TAG_LEFT, Vec3(-self.acc, 0.0, 0.0))
            self.sim.moveTaggedParticlesBy(TAG_RIGHT, Vec3(self.acc, 0.0, 0.0))
            self.acc = 0.0


loader = GripLoader(sim)
sim.addPreTimeStepRunnable(loader)

# --- output ----------------------------------------------------------------
sim.createCheckPointer(CheckPointPrms(
    fileNamePrefix="snap", beginTimeStep=0, endTimeStep=NSTEPS,
    timeStepIncr=SNAP_INCR))

sim.createFieldSaver(InteractionScalarFieldSaverPrms(
    interactionName="pp_bonds", fieldName="count", fileName="bond_count.dat",
    fileFormat="SUM", beginTimeStep=0, endTimeStep=NSTEPS,
    timeStepIncr=SNAP_INCR))

for tag, name in ((TAG_LEFT, "left"), (TAG_RIGHT, "right")):
    sim.createFieldSaver(TaggedParticleVectorFieldSaverPrms(
        tag=tag, mask=-1, fieldName="force",
        fileName="grip_force_%s.dat" % name, fileFormat="SUM",
        beginTimeStep=0, endTimeStep=NSTEPS, timeStepIncr=LOAD_INCR))
    sim.createFieldSaver(TaggedParticleVectorFieldSaverPrms(
        tag=tag, mask=-1, fieldName="displacement",
        fileName="grip_disp_%s.dat" % name, fileFormat="SUM",
        beginTimeStep=0, endTimeStep=NSTEPS, timeStepIncr=LOAD_INCR))

sim.run()
