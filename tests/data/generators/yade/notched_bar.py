# -*- coding: utf-8 -*-
# Notched bar of bonded spheres (JCFpm) pulled in tension along x until a crack runs through it.
# Generates the Yade importer test data of crackvis (see README.md next to this file). Run it through run.sh, or:
#     yade -j1 -n -x notched_bar.py <outdir>
# JCFpm writes cracks_<KEY>.txt into the current working directory; everything else goes to <outdir>:
# spheres.<iter>.vtu / intrs.<iter>.vtp (VTKRecorder), bonds.<iter>.txt (PyRunner) and history.txt (yade.plot).
import os, sys, time
from yade import pack, plot

OUT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else 'out') + '/'
os.makedirs(OUT, exist_ok=True)
KEY = 'notched_bar'

# ---------------------------------------------------------------- parameters
SEED = 7                    # fixed seed: the packing (and therefore the whole run) is reproducible with -j1
L, H, W = 0.06, 0.02, 0.02  # bar size along x, y, z [m], centred on the origin
RADIUS = 1.25e-3            # radius given to randomDensePack; its TriaxialTest grows the spheres (the mean radius ends at 1.77e-3)
FUZZ = 0.3                  # radii uniform in mean*(1 +- 0.3)
NOTCH_W = 0.003             # notch: slot of this width along x, centred on x=0 ...
NOTCH_Y = 0.0               # ... removing every sphere that touches the slot y > NOTCH_Y (half the height, from the top face)
INTR_R = 1.5                # interaction range for the first step only: bonds are created up to 1.5*(R1+R2)
STRAIN_RATE = 0.5           # UniaxialStrainer strain rate [1/s]; > 0 is tension
K = 400                     # record period [iterations]: VTKRecorder, bonds.<iter>.txt and plot.addData
NREC_MAX = 20               # safety stop: at most this many records after the one at iteration 0

# ---------------------------------------------------------------- packing with a notch
bar = pack.inAlignedBox((-L / 2, -H / 2, -W / 2), (L / 2, H / 2, W / 2))
notch = pack.inAlignedBox((-NOTCH_W / 2, NOTCH_Y, -W), (NOTCH_W / 2, H, W))
mat = O.materials.append(
        JCFpmMat(young=10e9, poisson=0.3, density=2500, frictionAngle=radians(30), cohesion=10e6, tensileStrength=2e6, label='rock')
)
t0 = time.time()
sp = pack.randomDensePack(bar - notch, radius=RADIUS, rRelFuzz=FUZZ, seed=SEED, returnSpherePack=True)
sp.toSimulation(material=mat)
print('packing: %d spheres in %.1f s' % (len(O.bodies), time.time() - t0))

bb = uniaxialTestFeatures(axis=0)
negIds, posIds, axis, area = bb['negIds'], bb['posIds'], bb['axis'], bb['area']
O.dt = 0.7 * PWaveTimeStep()

O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb(aabbEnlargeFactor=INTR_R, label='aabb')]),
        InteractionLoop(
                [Ig2_Sphere_Sphere_ScGeom6D(interactionDetectionFactor=INTR_R, label='ig2')],
                [Ip2_JCFpmMat_JCFpmMat_JCFpmPhys(cohesiveTresholdIteration=1)],
                # neverErase=False (default): a tensile break erases the interaction
                [Law2_ScGeom_JCFpmPhys_JointedCohesiveFrictionalPM(recordCracks=True, Key=KEY, label='law')],
        ),
        NewtonIntegrator(damping=0.4),
        UniaxialStrainer(
                strainRate=STRAIN_RATE,
                axis=axis,
                asymmetry=0,
                posIds=posIds,
                negIds=negIds,
                crossSectionArea=area,
                blockDisplacements=True,  # clamped ends: without this the notched bar opens like a hinge
                blockRotations=True,
                setSpeeds=True,
                label='strainer'
        ),
        VTKRecorder(fileName=OUT, recorders=['spheres', 'id', 'intr', 'jcfpm'], iterPeriod=K, label='vtk'),
        PyRunner(command='record()', iterPeriod=K, initRun=True, label='rec'),
]


def record():
	"""bonds.<iter>.txt (ground truth: every real sphere-sphere interaction, 'id1 id2 isCohesive') + one plot.addData row."""
	nCoh = 0
	with open(OUT + 'bonds.%d.txt' % O.iter, 'w') as f:
		for i in O.interactions:
			if not i.isReal:
				continue
			c = 1 if i.phys.isCohesive else 0
			nCoh += c
			f.write('%d %d %d\n' % (i.id1, i.id2, c))
	plot.addData(
	        iter=O.iter,
	        time=O.time,
	        stress=strainer.avgStress,
	        force=strainer.avgStress * area,
	        strain=strainer.strain,
	        tensCracks=law.nbTensCracks,
	        shearCracks=law.nbShearCracks,
	        cracks=law.nbTensCracks + law.nbShearCracks,
	        nIntr=O.interactions.countReal(),
	        nCohesive=nCoh
	)


def connected():
	"""True while a chain of real interactions still links the negative and the positive loaded end."""
	parent = list(range(len(O.bodies)))

	def find(a):
		while parent[a] != a:
			parent[a] = parent[parent[a]]
			a = parent[a]
		return a

	for i in O.interactions:
		if i.isReal:
			parent[find(i.id1)] = find(i.id2)
	return bool(set(find(a) for a in negIds) & set(find(a) for a in posIds))


nAfter = 0
t0 = time.time()
O.step()  # iteration 0: bonds are created here (and the first records are written, after the InteractionLoop)
ig2.interactionDetectionFactor = 1.
aabb.aabbEnlargeFactor = 1.
print('after iteration 0: %d real interactions, %d cohesive' % (O.interactions.countReal(), sum(1 for i in O.interactions if i.isReal and i.phys.isCohesive)))
for n in range(NREC_MAX):
	O.run(K - O.iter % K, True)  # stops just before the engines of iteration n*K run
	conn = connected()
	print(
	        'iter %d strain %.3e stress %.3e cracks %d (tensile %d shear %d) real intrs %d connected %s' % (
	                O.iter, strainer.strain, strainer.avgStress, law.nbTensCracks + law.nbShearCracks, law.nbTensCracks, law.nbShearCracks,
	                O.interactions.countReal(), conn
	        )
	)
	O.step()  # iteration n*K: VTKRecorder and PyRunner write their records
	if not conn:
		nAfter += 1
		if nAfter > 1:  # stop after one more record once the two loaded ends are no longer linked
			break
plot.saveDataTxt(OUT + 'history.txt')
print('run: %.1f s, last record iter %d, ends still connected: %s, bodies %d, area %g' % (time.time() - t0, O.iter - 1, connected(), len(O.bodies), area))
