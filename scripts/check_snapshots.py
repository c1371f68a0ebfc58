#!/usr/bin/env python3
"""CI check that the community's tools open sphdisk's snapshots.

1. yt's SWIFT front end loads a 3D, a 2D and a 1D snapshot: the particle count and total
   mass equal the header's and the particles' own, and the SPH density field is the one
   stored (the 2D one is Σ: yt labels every `Densities` mass/length³).
2. h5py reads a snapshot split over several files (SWIFT's multi-file convention): the
   parts' NumPart_ThisFile add up to NumPart_Total and together hold every particle once;
   scripts/virtual_snapshot.py writes SWIFT's virtual file beside them, which yt and
   swiftsimio open whole, and sphdisk reads back (render).
3. swiftsimio (SWIFT's own reader) loads a 3D and a 2D snapshot with units: every
   particle, the stored masses and densities, the header's time and dimension.
4. With physical units ([units]), `Temperatures` in K: swiftsimio and yt read them.
5. Where yt puts a disk and what it calls its units (README, "Snapshots in yt"): yt's SWIFT
   front end fixes the domain's left edge at 0 (particles at negative coordinates are not
   read), so the run's origin is at `Header/Shift` in yt; the ring's central mass is there,
   its gas is centred on it, and a projection centred on it is made. yt takes the units
   from `/Units` only (its `units_override` is overwritten by the front end): with
   Phantom's units in `[units]` (M_sun, au, G = 1) yt's lengths are in au, and the 2D
   `Densities` relabelled mass/length² equal the file's Σ in g/cm² (and swiftsimio's).

Usage: scripts/check_snapshots.py [path/to/sphdisk]   (default target/release/sphdisk)
"""
import pathlib
import subprocess
import sys
import tempfile

import h5py
import numpy as np
import swiftsimio
import yt

yt.set_log_level(40)
root = pathlib.Path(__file__).resolve().parent.parent
exe = sys.argv[1] if len(sys.argv) > 1 else str(root / "target/release/sphdisk")


def run(problem, out, *sets):
    args = [exe, "run", str(root / "problems" / problem), "--quiet", "--out", str(out)]
    for s in sets:
        args += ["--set", s]
    subprocess.run(args, check=True)


with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)

    def yt_check(snap, n_expected, dim):
        """yt opens `snap` whole: count, total mass and densities are the file's."""
        with h5py.File(snap, "r") as f:
            n_header = int(f["Header"].attrs["NumPart_Total"][0])
            mass_h5 = float(f["PartType0/Masses"][:].sum())
            rho_h5 = np.sort(f["PartType0/Densities"][:])
            assert int(f["HydroScheme"].attrs["Dimension"][0]) == dim
        ds = yt.load(str(snap))
        assert type(ds).__name__ == "SwiftDataset", type(ds)
        # yt's particle index takes three axes: the header says 3 for 1D and 2D files too.
        assert ds.dimensionality == 3
        ad = ds.all_data()
        mass = ad["PartType0", "Mass"]
        assert len(mass) == n_header == n_expected, (len(mass), n_header, n_expected)
        # The same numbers summed in another order: equal to round-off.
        assert abs(float(mass.sum()) - mass_h5) <= 1e-12 * mass_h5, (float(mass.sum()), mass_h5)
        rho = np.sort(np.asarray(ad["gas", "density"]))
        assert np.array_equal(rho, rho_h5), "yt's gas density is not the stored one"
        assert rho.min() > 0
        print(f"yt: {dim}D {snap.name}, SwiftDataset, {len(mass)} particles, "
              f"mass {float(mass.sum()):.15g}, density {rho.min():.4g}..{rho.max():.4g}")
        return ds

    # 1. yt on a 3D snapshot (Sedov blast, 20³ particles), a 2D one (the spreading ring,
    #    with its central point mass) and a 1D one (Sod).
    run("sedov.toml", tmp / "s3", "particles.n=20", "time.end=0.01", "output.interval=0.01")
    snap = tmp / "s3" / "snap_0001.hdf5"
    yt_check(snap, 20**3, 3)
    run("ring.toml", tmp / "r", "particles.n=20", "ring.tau_end=0.017",
        "output.interval=0.01")
    ring_snap = tmp / "r" / "snap_0001.hdf5"
    with h5py.File(ring_snap, "r") as f:
        n_ring = int(f["Header"].attrs["NumPart_Total"][0])
    ds = yt_check(ring_snap, n_ring, 2)
    # The point mass (SWIFT's sink type) is there too.
    assert len(ds.all_data()["PartType3", "Mass"]) == 1
    run("sod.toml", tmp / "s1", "particles.n=200", "time.end=0.01", "output.interval=0.01")
    yt_check(tmp / "s1" / "snap_0001.hdf5", 200 + 25, 1)

    # 2. h5py on a multi-file snapshot (2D Sedov, 3 files per snapshot).
    # With an AV switch, so that each particle's α (ViscosityParameters) is written too.
    run("sedov2d.toml", tmp / "m", "particles.n=30", "time.end=0.01",
        "output.interval=0.01", "output.files_per_snapshot=3",
        'artificial_viscosity.switch="morris_monaghan"')
    parts = sorted((tmp / "m").glob("snap_0001.*.hdf5"))
    assert len(parts) == 3, parts
    ids, counts = [], []
    for k, path in enumerate(parts):
        with h5py.File(path, "r") as f:
            h = f["Header"].attrs
            # SWIFT writes numbers as 1-element arrays.
            assert h["NumFilesPerSnapshot"].shape == (1,) and h["NumFilesPerSnapshot"][0] == 3
            assert h["ThisFile"][0] == k
            total = int(h["NumPart_Total"][0])
            counts.append(int(h["NumPart_ThisFile"][0]))
            ids.append(f["PartType0/ParticleIDs"][:])
            assert f["PartType0/Coordinates"].shape == (counts[-1], 3)
    ids = np.concatenate(ids)
    assert sum(counts) == total == 900, (counts, total)
    assert len(np.unique(ids)) == total, "a particle is missing or repeated"
    print(f"h5py: multi-file snapshot, {len(parts)} files, {counts} = {total} particles")
    # A part alone is a third of the particles to yt and swiftsimio; the virtual file is all.
    subprocess.run([sys.executable, str(root / "scripts/virtual_snapshot.py"),
                    str(parts[0])], check=True)
    virtual = tmp / "m" / "snap_0001.hdf5"
    ds = yt_check(virtual, 900, 2)
    assert np.array_equal(np.sort(np.asarray(ds.all_data()["PartType0", "ParticleIDs"])),
                          np.sort(ids))
    data = swiftsimio.load(str(virtual))
    assert not data.metadata.partial_snapshot
    assert len(data.gas.masses) == 900
    assert np.array_equal(np.sort(np.asarray(data.gas.particle_ids)), np.sort(ids))
    alpha = np.asarray(data.gas.viscosity_parameters)
    # The switch keeps α between α_min = 0.1 and α = 1 (problems/sedov2d.toml).
    assert len(alpha) == 900 and alpha.min() >= 0.1 and alpha.max() <= 1.0, alpha
    print(f"swiftsimio: virtual file of {len(parts)} parts, {len(data.gas.masses)} particles, "
          f"α {alpha.min():.3f}–{alpha.max():.3f}")
    # sphdisk follows the virtual file to its parts.
    subprocess.run([exe, "render", str(virtual), "--out", str(tmp / "m" / "v.png")],
                   check=True, stdout=subprocess.DEVNULL)
    assert (tmp / "m" / "v.png").stat().st_size > 0

    # 3. swiftsimio on the 3D Sedov snapshot and a 2D one (the spreading ring).
    for path, dim in [(snap, 3), (ring_snap, 2)]:
        with h5py.File(path, "r") as f:
            n = int(f["Header"].attrs["NumPart_Total"][0])
            t = float(f["Header"].attrs["Time"][0])
            m_h5 = f["PartType0/Masses"][:]
            rho_h5 = f["PartType0/Densities"][:]
        data = swiftsimio.load(str(path))
        gas = data.gas
        assert len(gas.masses) == n > 0, (len(gas.masses), n)
        assert np.array_equal(np.asarray(gas.masses), m_h5)
        assert np.array_equal(np.asarray(gas.densities), rho_h5)
        # Densities carry mass / length^dimension (Σ in 2D).
        assert gas.densities.units.dimensions == (
            gas.masses.units.dimensions / gas.coordinates.units.dimensions**dim), (
            gas.densities.units)
        assert abs(float(data.metadata.time.value) - t) <= 1e-12 * max(t, 1.0)
        print(f"swiftsimio {swiftsimio.__version__}: {dim}D, {n} particles, "
              f"density in {gas.densities.units}, t = {t}")
    # 4. Temperatures in K where the problem file gives physical units: swiftsimio reads them
    #    in K and they are μ m_p P/(ρ k_B) of the stored P and ρ; yt's gas temperature is
    #    the same field. Without [units] there are none (G = 1 units have no kelvin).
    run("sedov.toml", tmp / "u", "particles.n=12", "time.end=0.01", "output.interval=0.01",
        "units.mass_cgs=2e33", "units.length_cgs=1.5e13", "units.time_cgs=3.15e7",
        "units.mean_molecular_weight=1.3")
    usnap = tmp / "u" / "snap_0001.hdf5"
    with h5py.File(usnap, "r") as f:
        g = f["PartType0"]
        p_cgs = g["Pressures"][:] * g["Pressures"].attrs[
            "Conversion factor to CGS (not including cosmological corrections)"][0]
        rho_cgs = g["Densities"][:] * g["Densities"].attrs[
            "Conversion factor to CGS (not including cosmological corrections)"][0]
        t_file = g["Temperatures"][:]
    m_p, k_b = 1.67262192369e-24, 1.380649e-16
    t_expect = 1.3 * m_p * p_cgs / (rho_cgs * k_b)
    # The same product in another order: round-off.
    assert np.allclose(t_file, t_expect, rtol=1e-12, atol=0), "Temperatures"
    data = swiftsimio.load(str(usnap))
    temps = data.gas.temperatures
    assert str(temps.units) == "K", temps.units
    assert np.array_equal(np.asarray(temps.to("K")), t_file)
    ds = yt.load(str(usnap))
    # yt's SWIFT front end knows the units of a few fields only: the values, unitless.
    t_yt = np.sort(np.asarray(ds.all_data()["gas", "temperature"]))
    assert np.array_equal(t_yt, np.sort(t_file)), "yt's gas temperature"
    with h5py.File(snap, "r") as f:
        assert "Temperatures" not in f["PartType0"], "no kelvin without [units]"
    print(f"Temperatures: {t_file.min():.4g}..{t_file.max():.4g} K (swiftsimio, yt)")

    # 5. The disk's centre in yt, and yt's units of a G = 1 disk in Phantom's units.
    ds = yt.load(str(ring_snap))
    ad = ds.all_data()
    shift = ds.arr(np.asarray(ds.parameters["header"]["Shift"], dtype=float), "code_length")
    star = ad["PartType3", "Coordinates"][0]
    assert np.array_equal(np.asarray(star), np.asarray(shift)), (star, shift)
    pos = ad["PartType0", "Coordinates"]
    m = ad["PartType0", "Mass"]
    com = (pos * m[:, None]).sum(axis=0) / m.sum() - shift
    assert float(np.abs(com[:2]).max()) < 0.05 and float(com[2]) == 0.0, com
    png = yt.ProjectionPlot(ds, "z", ("gas", "density"), center=shift,
                            width=(4, "code_length")).save(str(tmp / "ring_yt.png"))
    assert pathlib.Path(png[0]).stat().st_size > 0, png
    print(f"yt: the ring's centre is Header/Shift = {np.asarray(shift)}, gas centre of mass "
          f"- Shift = {np.asarray(com)}, projection {pathlib.Path(png[0]).name}")
    msun, au, g_cgs = 1.98847e33, 1.495978707e13, 6.6743e-8
    t_unit = (au**3 / (g_cgs * msun)) ** 0.5
    run("ring.toml", tmp / "ru", "particles.n=20", "ring.tau_end=0.017",
        "output.interval=0.01", f"units.mass_cgs={msun}", f"units.length_cgs={au}",
        f"units.time_cgs={t_unit}")
    usnap = tmp / "ru" / "snap_0001.hdf5"
    ds = yt.load(str(usnap), units_override={"length_unit": (1.0, "pc")})
    assert abs(float(ds.length_unit.to("AU")) - 1.0) < 1e-9, ds.length_unit
    rho_code = ds.all_data()["gas", "density"].to("code_mass/code_length**3").d
    sigma_yt = ds.arr(rho_code, "code_mass/code_length**2")
    with h5py.File(usnap, "r") as f:
        rho = f["PartType0/Densities"]
        sigma_h5 = rho[:] * rho.attrs[
            "Conversion factor to CGS (not including cosmological corrections)"][0]
    assert np.allclose(np.sort(sigma_yt.to("g/cm**2").d), np.sort(sigma_h5), rtol=1e-12,
                       atol=0), "Σ in g/cm²"
    # swiftsimio expresses the same factor in its own solar mass: equal to 1e-4.
    sigma_ss = swiftsimio.load(str(usnap)).gas.densities
    assert np.allclose(np.sort(sigma_ss.to("g/cm**2").value), np.sort(sigma_h5), rtol=1e-4,
                       atol=0), "swiftsimio's Σ in g/cm²"
    print(f"yt: G = 1 ring in [units] M_sun, au: length unit {ds.length_unit.to('AU')}, "
          f"Σ {sigma_yt.to('g/cm**2').d.min():.4g}..{sigma_yt.to('g/cm**2').d.max():.4g} "
          f"g/cm² (= h5py's, swiftsimio's)")
print("snapshot checks passed")
