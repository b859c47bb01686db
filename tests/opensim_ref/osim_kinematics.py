"""OpenSim's own kinematics of a model, for the conversion tests (run in a subprocess: the
``opensim`` wheel cannot share a process with ``casadi``, hence with ``gdimitate``).

Usage: ``python osim_kinematics.py MODEL.osim OUT.npz (--mot FILE.mot | --q IN.npz)``

``--mot``: every row of an OpenSim coordinates file (degrees converted by OpenSim's own
rules); ``--q``: an ``.npz`` with ``names`` (n,) and ``q`` (T, n) in radians/metres.
Writes ``OUT.npz``: ``names``/``q`` (the coordinate values used, rad/m), ``bodies`` (nb,),
``body_p`` (T, nb, 3) body origins and ``body_R`` (T, nb, 3, 3) orientations in ground,
``body_mass`` (nb,), ``body_com`` (nb, 3) and ``body_inertia`` (nb, 3, 3) (about the centre of
mass, body frame), ``com`` (T, 3), ``mass``, ``markers`` (nm,), ``marker_p`` (T, nm, 3),
``coordinates`` (all, nc) with their ``ranges`` (nc, 2), ``seconds`` (model load + all frames).
"""

import sys
import time

import numpy as np
import opensim as osim


def main(model_path, out, mode, src):
    t0 = time.perf_counter()
    osim.Logger.removeFileSink()  # else opensim.log lands next to the model file
    model = osim.Model(model_path)
    state = model.initSystem()
    cs = model.getCoordinateSet()
    if mode == "--mot":
        sto = osim.Storage(src)
        if sto.isInDegrees():
            model.getSimbodyEngine().convertDegreesToRadians(sto)
        arr = sto.getColumnLabels()
        labels = [arr.get(i) for i in range(1, arr.getSize())]  # without "time"
        names = [n for n in labels if cs.contains(n)]
        q = np.zeros((sto.getSize(), len(names)))
        for t in range(sto.getSize()):
            row = sto.getStateVector(t).getData()
            vals = [row.get(i) for i in range(row.getSize())]
            q[t] = [vals[labels.index(n)] for n in names]
    else:
        d = np.load(src)
        names, q = [str(n) for n in d["names"]], np.asarray(d["q"], float)
    bodies = [model.getBodySet().get(i) for i in range(model.getBodySet().getSize())]
    markers = [model.getMarkerSet().get(i) for i in range(model.getMarkerSet().getSize())]
    T = q.shape[0]
    body_p = np.zeros((T, len(bodies), 3))
    body_R = np.zeros((T, len(bodies), 3, 3))
    marker_p = np.zeros((T, len(markers), 3))
    com = np.zeros((T, 3))
    coords = [cs.get(n) for n in names]
    for t in range(T):
        for c, v in zip(coords, q[t]):
            c.setValue(state, float(v), False)
        model.realizePosition(state)
        for i, b in enumerate(bodies):
            X = b.getTransformInGround(state)
            body_p[t, i] = X.p().to_numpy()
            body_R[t, i] = np.array([[X.R().get(r, k) for k in range(3)] for r in range(3)])
        for i, m in enumerate(markers):
            marker_p[t, i] = m.getLocationInGround(state).to_numpy()
        com[t] = model.calcMassCenterPosition(state).to_numpy()
    inertia = np.zeros((len(bodies), 3, 3))
    for i, b in enumerate(bodies):
        I = b.getInertia()  # about the body's centre of mass, body frame
        m, p = I.getMoments().to_numpy(), I.getProducts().to_numpy()  # xx yy zz, xy xz yz
        inertia[i] = [[m[0], p[0], p[1]], [p[0], m[1], p[2]], [p[1], p[2], m[2]]]
    all_coords = [cs.get(i) for i in range(cs.getSize())]
    np.savez(out, names=np.array(names), q=q, bodies=np.array([b.getName() for b in bodies]),
             body_mass=np.array([b.getMass() for b in bodies]),
             body_com=np.array([b.getMassCenter().to_numpy() for b in bodies]),
             body_inertia=inertia, coordinates=np.array([c.getName() for c in all_coords]),
             ranges=np.array([[c.getRangeMin(), c.getRangeMax()] for c in all_coords]),
             body_p=body_p, body_R=body_R, com=com, mass=model.getTotalMass(state),
             markers=np.array([m.getName() for m in markers]), marker_p=marker_p,
             seconds=time.perf_counter() - t0)


if __name__ == "__main__":
    main(*sys.argv[1:5])
