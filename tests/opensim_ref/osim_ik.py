"""OpenSim's own inverse kinematics of a marker file, for tests/io/test_opensim_ik.py (run in a
subprocess: the ``opensim`` wheel cannot share a process with ``casadi``, hence gdimitate).

Usage: ``python osim_ik.py MODEL.osim MARKERS.trc OUT.npz T0 T1 [WEIGHTS.json]``

Runs OpenSim's ``InverseKinematicsTool`` on ``MARKERS.trc`` over ``[T0, T1]`` s with one
``IKMarkerTask`` per model marker present in the file (weight from ``WEIGHTS.json``, a
``{marker: weight}`` object, default 1), accuracy 1e-6, then OpenSim's own forward kinematics
of the result. Writes ``OUT.npz``: ``t`` (T,), ``names`` (nc,) coordinates and ``q`` (T, nc)
[rad, m], ``markers`` (nm,) and ``marker_p`` (T, nm, 3) model markers in ground [m],
``seconds`` (the IK tool's run).
"""

import json
import os
import sys
import tempfile
import time

import numpy as np
import opensim as osim


def main(model_path, trc, out, t0, t1, weights=None):
    osim.Logger.removeFileSink()
    w = json.load(open(weights)) if weights else {}
    model = osim.Model(model_path)
    model.initSystem()
    table = osim.TimeSeriesTableVec3(trc)
    in_file = set(table.getColumnLabels())
    ms = model.getMarkerSet()
    tasks = osim.IKTaskSet()
    for i in range(ms.getSize()):
        name = ms.get(i).getName()
        task = osim.IKMarkerTask()
        task.setName(name)
        task.setApply(name in in_file)
        task.setWeight(float(w.get(name, 1.0)))
        tasks.cloneAndAppend(task)
    tmp = tempfile.mkdtemp()
    mot = os.path.join(tmp, "ik.mot")
    tool = osim.InverseKinematicsTool()
    tool.setModel(model)
    tool.set_IKTaskSet(tasks)
    tool.setMarkerDataFileName(trc)
    tool.setStartTime(float(t0))
    tool.setEndTime(float(t1))
    tool.set_accuracy(1e-6)
    tool.set_report_errors(False)
    tool.setResultsDir(tmp)
    tool.setOutputMotionFileName(mot)
    start = time.perf_counter()
    tool.run()
    seconds = time.perf_counter() - start
    sto = osim.Storage(mot)
    if sto.isInDegrees():
        model.getSimbodyEngine().convertDegreesToRadians(sto)
    state = model.initSystem()
    cs = model.getCoordinateSet()
    labels = sto.getColumnLabels()
    cols = [labels.get(i) for i in range(1, labels.getSize())]
    names = [n for n in cols if cs.contains(n)]
    T = sto.getSize()
    q = np.zeros((T, len(names)))
    t = np.zeros(T)
    mp = np.zeros((T, ms.getSize(), 3))
    for k in range(T):
        row = sto.getStateVector(k)
        t[k] = row.getTime()
        data = row.getData()
        vals = [data.get(i) for i in range(data.getSize())]
        q[k] = [vals[cols.index(n)] for n in names]
        for n, v in zip(names, q[k]):
            cs.get(n).setValue(state, float(v), False)
        model.realizePosition(state)
        for i in range(ms.getSize()):
            mp[k, i] = ms.get(i).getLocationInGround(state).to_numpy()
    np.savez(out, t=t, names=np.array(names), q=q, marker_p=mp, seconds=seconds,
             markers=np.array([ms.get(i).getName() for i in range(ms.getSize())]))


if __name__ == "__main__":
    main(*sys.argv[1:])
