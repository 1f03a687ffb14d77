# -*- coding: utf-8 -*-
# A notched bar of about 11,000 bonded spheres (JCFpm) pulled in tension along x until it separates:
# the coverage specimens of crackvis (docs/methods.md, "Coverage on Yade's packings"). Run it through
# tension_runs.sh, or:
#     yade -j1 -n -x tension_bar.py hexa|random <outdir>
# packing 'hexa': pack.regularHexa (equal radii, a hexagonal close packing);
# packing 'random': pack.randomDensePack (radii +-30 %, periodic compaction tiled over the bar).
# JCFpm writes cracks_<KEY>.txt into the current working directory; everything else goes to <outdir>:
# spheres.<iter>.vtu / intrs.<iter>.vtp (VTKRecorder), bonds.<iter>.txt (PyRunner), history.txt.
# Only the first record (the intact bar) and the last ones are written: what a coverage check needs.
import os, sys, time
from yade import pack, plot

PACKING = sys.argv[1] if len(sys.argv) > 1 else 'hexa'
OUT = os.path.abspath(sys.argv[2] if len(sys.argv) > 2 else 'out') + '/'
os.makedirs(OUT, exist_ok=True)
KEY = 'tension_' + PACKING
assert PACKING in ('hexa', 'random'), 'packing: hexa or random'

SEED = 11
L, H, W = 0.08, 0.03, 0.03     # bar [m], centred on the origin, long axis x
NOTCH_W, NOTCH_DEPTH = 0.003, 0.0075  # a slot from the top face, a quarter of the height deep
INTR_R = 1.5 if PACKING == 'random' else 1.05  # bonds up to this factor x (R1+R2) at iteration 0
STRAIN_RATE = 0.5
K = 500                        # iterations between the separation checks
NREC_MAX = 60

bar = pack.inAlignedBox((-L / 2, -H / 2, -W / 2), (L / 2, H / 2, W / 2))
notch = pack.inAlignedBox((-NOTCH_W / 2, H / 2 - NOTCH_DEPTH, -W), (NOTCH_W / 2, H, W))
mat = O.materials.append(
        JCFpmMat(young=10e9, poisson=0.3, density=2500, frictionAngle=radians(30), cohesion=10e6, tensileStrength=2e6, label='rock')
)
t0 = time.time()
if PACKING == 'hexa':
	sp = pack.regularHexa(bar - notch, radius=1.07e-3, gap=0, material=mat)
	O.bodies.append(sp)
else:
	sp = pack.randomDensePack(bar - notch, radius=0.98e-3, rRelFuzz=0.3, spheresInCell=2000, seed=SEED, returnSpherePack=True, memoizeDb=None)
	sp.toSimulation(material=mat)
print('packing %s: %d spheres in %.1f s' % (PACKING, len(O.bodies), time.time() - t0))

bb = uniaxialTestFeatures(axis=0)
negIds, posIds, axis, area = bb['negIds'], bb['posIds'], bb['axis'], bb['area']
O.dt = 0.7 * PWaveTimeStep()

O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=INTR_R, label='aabb')]),
        InteractionLoop(
                [Ig2_Sphere_Sphere_ScGeom6D(interactionDetectionFactor=INTR_R, label='ig2')],
                [Ip2_JCFpmMat_JCFpmMat_JCFpmPhys(cohesiveTresholdIteration=1)],
                [Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM(recordCracks=True, Key=KEY, label='law')],
        ),
        NewtonIntegrator(damping=0.4),
        UniaxialStrainer(
                strainRate=STRAIN_RATE, axis=axis, asymmetry=0, posIds=posIds, negIds=negIds, crossSectionArea=area,
                blockDisplacements=True, blockRotations=True, setSpeeds=True, label='strainer'
        ),
        VTKRecorder(fileName=OUT, recorders=['spheres', 'id', 'intr', 'jcfpm'], iterPeriod=K, dead=True, label='vtk'),
]


def record():
	vtk.dead = False
	O.step()  # this iteration's VTKRecorder writes (it runs after the InteractionLoop)
	vtk.dead = True
	nCoh = 0
	with open(OUT + 'bonds.%d.txt' % (O.iter - 1), 'w') as f:
		for i in O.interactions:
			if i.isReal:
				c = 1 if i.phys.isCohesive else 0
				nCoh += c
				f.write('%d %d %d\n' % (i.id1, i.id2, c))
	plot.addData(iter=O.iter - 1, time=O.time, stress=strainer.avgStress, strain=strainer.strain,
	             tensCracks=law.nbTensCracks, shearCracks=law.nbShearCracks, cracks=law.nbTensCracks + law.nbShearCracks, nCohesive=nCoh)


def connected():
	"""True while a chain of bonds (cohesive interactions) still links the two loaded ends."""
	parent = list(range(len(O.bodies)))

	def find(a):
		while parent[a] != a:
			parent[a] = parent[parent[a]]
			a = parent[a]
		return a

	for i in O.interactions:
		if i.isReal and i.phys.isCohesive:  # a contact that lost its bond carries no tension
			parent[find(i.id1)] = find(i.id2)
	return bool(set(find(a) for a in negIds) & set(find(a) for a in posIds))


t0 = time.time()
vtk.iterPeriod = 1
record()  # iteration 0: the bonds are created and the intact bar written
ig2.interactionDetectionFactor = 1.
aabb.aabbEnlargeFactor = 1.
print('after iteration 0: %d real interactions, %d cohesive' % (O.interactions.countReal(), sum(1 for i in O.interactions if i.isReal and i.phys.isCohesive)))
# Stop rule: the ends no longer linked by bonds, or the stress fallen below 2 % of its peak (a few
# bonds near the notch or the clamps may hold on while the section is cut through).
after = 0
peak = 0.0
for n in range(NREC_MAX):
	O.run(K, True)
	conn = connected()
	peak = max(peak, strainer.avgStress)
	print('iter %d strain %.3e stress %.3e cracks %d (tensile %d shear %d) connected %s  %.0f s' % (
	        O.iter, strainer.strain, strainer.avgStress, law.nbTensCracks + law.nbShearCracks, law.nbTensCracks, law.nbShearCracks, conn, time.time() - t0))
	if not conn or strainer.avgStress < 0.02 * peak:
		record()
		after += 1
		if after > 1:
			break
plot.saveDataTxt(OUT + 'history.txt')
print('run: %.1f s, ends still connected: %s, bodies %d' % (time.time() - t0, connected(), len(O.bodies)))
