"""The texwarp Python module as installed (PYTHONPATH at the install prefix's site-packages): local jobs (the runner
in-process), jobs on a real texwarpd on loopback (started here), errors as exceptions with the problem's path, arrays
warped in memory (warp, map_points) against the same files through run_local and the CLI, the type stubs.
Environment: TEXWARP_PREFIX (the install prefix), TEXWARPD and TEXWARP_CLI (binaries), TEXWARP_SOURCE_DIR."""

import ast
import json
import os
import shutil
import struct
import subprocess
import tempfile
import threading
import time
import unittest
import zlib

import numpy as np

import texwarp

SOURCE_DIR = os.environ["TEXWARP_SOURCE_DIR"]
SHEET_JOB = os.path.join(SOURCE_DIR, "examples", "sheet-mesh-job.json")


def sheet_job():
    with open(SHEET_JOB) as f:
        job = json.load(f)
    job["options"] = {"device": "cpu"}
    return job


def read_json(path):
    with open(path) as f:
        return json.load(f)


def broken_mesh_job(source):
    """A mesh job whose OBJ has a face that names vertex 7 of 3."""
    return {"image": {"path": os.path.join(SOURCE_DIR, "examples", "astronaut.png")},
            "mesh": {"source": source, "features": {"features": [{"source": [10, 10], "target": {"vertex": 0}}]}},
            "options": {"device": "cpu"}}


class Folder:
    def __enter__(self):
        self.path = tempfile.mkdtemp(prefix="texwarp-pytest-")
        return self.path

    def __exit__(self, *exc):
        shutil.rmtree(self.path, ignore_errors=True)


class Server:
    """texwarpd on 127.0.0.1 at a free port (--port-file), killed afterwards."""

    def __enter__(self):
        self.dir = tempfile.mkdtemp(prefix="texwarp-pyserver-")
        port_file = os.path.join(self.dir, "port")
        self.log = open(os.path.join(self.dir, "log"), "w")
        self.proc = subprocess.Popen([os.environ["TEXWARPD"], "--listen", "127.0.0.1:0", "--data-dir",
                                      os.path.join(self.dir, "data"), "--port-file", port_file, "--device", "cpu"],
                                     stdout=self.log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            port = ""
            if os.path.exists(port_file):
                with open(port_file) as f:
                    port = f.read().strip()
            if port:
                self.url = "http://127.0.0.1:" + port
                return self
            if self.proc.poll() is not None:
                break
            time.sleep(0.05)
        raise RuntimeError("texwarpd did not come up: " + open(os.path.join(self.dir, "log")).read())

    def __exit__(self, *exc):
        self.proc.kill()
        self.proc.wait()
        self.log.close()
        shutil.rmtree(self.dir, ignore_errors=True)


class InstalledModule(unittest.TestCase):
    def test_imported_from_the_install_prefix(self):
        prefix = os.path.realpath(os.environ["TEXWARP_PREFIX"])
        self.assertTrue(os.path.realpath(texwarp.__file__).startswith(prefix), texwarp.__file__)
        self.assertTrue(os.path.realpath(texwarp._texwarp.__file__).startswith(prefix))

    def test_the_image_module_is_installed_beside_the_extension(self):
        # Formats other than PNG go through libtexwarp_image_oiio.so, which the package carries beside _texwarp.
        folder = os.path.dirname(os.path.realpath(texwarp._texwarp.__file__))
        self.assertTrue(os.path.isfile(os.path.join(folder, "libtexwarp_image_oiio.so")), os.listdir(folder))
        with Folder() as out:
            job = {"image": {"path": os.path.join(SOURCE_DIR, "examples", "astronaut.png")},
                   "warp": {"features": []}, "output": {"file_format": "tiff"}, "options": {"device": "cpu"}}
            result = texwarp.run_local(job, out)
            self.assertEqual(result["state"], "succeeded")
            tiffs = [f for f in result["files"] if f.endswith(".tif") or f.endswith(".tiff")]
            self.assertEqual(len(tiffs), 1, result["files"])
            with open(tiffs[0], "rb") as f:
                self.assertIn(f.read(4), (b"II*\0", b"MM\0*"))


class LocalJobs(unittest.TestCase):
    def check_sheet_result(self, result, out):
        names = sorted(os.path.basename(f) for f in result["files"])
        self.assertEqual(names, ["mesh.obj", "report.json", "uvs.json", "warped.png"])
        for f in result["files"]:
            self.assertTrue(os.path.isfile(f) and os.path.dirname(f) == out, f)
        self.assertEqual(result["state"], "succeeded")
        report = result["report"]
        self.assertEqual(report, read_json(os.path.join(out, "report.json")))
        mesh = report  # a mesh job's report holds the mapping's fields at its top level
        self.assertEqual(mesh["flipped_triangles"], 0)
        # Each pinned vertex's UV in uvs.json, back in texture pixels, is its feature's source (an independent
        # computation of the residuals the report gives).
        uvs = read_json(os.path.join(out, "uvs.json"))
        w, h = uvs["texture"]["width"], uvs["texture"]["height"]
        self.assertEqual((w, h), (128, 128))
        job = sheet_job()
        worst = 0.0
        for feature in job["mesh"]["features"]["features"]:
            i = uvs["vertices"].index(feature["target"]["vertex"])
            u, v = uvs["uv"][i]
            x, y = u * w, (1.0 - v) * h  # uv_origin bottom_left
            worst = max(worst, abs(x - feature["source"][0]), abs(y - feature["source"][1]))
        self.assertLess(worst, 0.05)
        self.assertAlmostEqual(mesh["max_residual_px"], worst, delta=0.02)
        return uvs

    def test_run_local_matches_the_command_line(self):
        with Folder() as out, Folder() as cli_out:
            seen = []
            result = texwarp.run_local(sheet_job(), out, progress=lambda f, s: seen.append((f, s)))
            uvs = self.check_sheet_result(result, out)
            self.assertTrue(seen, "progress was never called")
            fractions = [f for f, _ in seen]
            self.assertEqual(fractions, sorted(fractions))
            self.assertEqual(seen[-1], (1.0, "succeeded"))
            job_file = os.path.join(cli_out, "job.json")
            with open(job_file, "w") as f:
                json.dump(sheet_job(), f)
            subprocess.run([os.environ["TEXWARP_CLI"], "run", job_file, "--out", cli_out, "--quiet"], check=True)
            cli_uvs = read_json(os.path.join(cli_out, "uvs.json"))
            self.assertEqual(cli_uvs["vertices"], uvs["vertices"])
            for a, b in zip(cli_uvs["uv"], uvs["uv"]):
                self.assertAlmostEqual(a[0], b[0], places=12)
                self.assertAlmostEqual(a[1], b[1], places=12)

    def test_submit_local_polls_without_blocking_then_fetches(self):
        job = texwarp.submit_local(sheet_job())
        self.assertTrue(job.id.startswith("local:"))
        polls = 0
        while not job.poll():
            self.assertIn(job.state, ("queued", "running"))
            self.assertTrue(0.0 <= job.progress <= 1.0)
            polls += 1
            time.sleep(0.005)
        self.assertEqual(job.state, "succeeded")
        self.assertIsNone(job.error)
        with Folder() as out:
            self.check_sheet_result(job.fetch(out), out)

    def test_a_wrong_job_raises_input_error_with_its_path(self):
        job = sheet_job()
        job["mesh"]["features"]["features"][2]["target"]["vertex"] = 9999
        with self.assertRaises(texwarp.InputError) as raised:
            texwarp.run_local(job, tempfile.gettempdir())
        self.assertEqual(raised.exception.path, "$.mesh.features.features[2].target.vertex")
        self.assertIn("9999", raised.exception.detail)
        self.assertEqual(raised.exception.type, "urn:texwarp:problem:invalid-job")
        job = sheet_job()
        job["output"]["colour"] = 1
        with self.assertRaises(texwarp.ProblemError) as raised:
            texwarp.submit_local(job)
        self.assertEqual(raised.exception.path, "$.output.colour")
        with self.assertRaises(texwarp.InputError) as raised:
            texwarp.run_local({"image": {"path": "no-such.png"}, "warp": {"features": []}}, tempfile.gettempdir(),
                              base_dir=tempfile.gettempdir())
        self.assertEqual(raised.exception.path, "$.image.path")

    def test_a_job_found_wrong_while_it_runs_raises_input_error(self):
        # A path mesh is parsed only when the job runs (submit_local plans without it): the job fails on its thread.
        with Folder() as folder:
            obj = os.path.join(folder, "broken.obj")
            with open(obj, "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
            handle = texwarp.submit_local(broken_mesh_job({"path": "broken.obj"}), base_dir=folder)
            with self.assertRaises(texwarp.InputError) as raised:
                handle.wait(timeout=60)
            self.assertEqual(raised.exception.path, "$.mesh.source")
            self.assertIn("vertex 7", raised.exception.detail)
            self.assertEqual(handle.state, "failed")
            self.assertEqual(handle.error["path"], "$.mesh.source")

    def test_fetch_before_the_end_and_cancel(self):
        # An exact 2048² warp with 40 features runs for seconds on the CPU backend: canceled long before it ends.
        job = {"image": {"path": os.path.join(SOURCE_DIR, "examples", "astronaut.png")},
               "warp": {"features": [{"source": [100 + 37 * (i % 8), 100 + 41 * (i // 8)],
                                      "target": [104 + 37 * (i % 8), 98 + 41 * (i // 8)]} for i in range(40)]},
               "output": {"width": 2048, "height": 2048}, "options": {"exact": True, "device": "cpu"}}
        handle = texwarp.submit_local(job)
        with self.assertRaises(texwarp.Error):
            handle.fetch(tempfile.gettempdir())
        handle.cancel()
        with self.assertRaises(texwarp.JobCanceledError):
            handle.wait(timeout=60)
        self.assertEqual(handle.state, "canceled")


class ServerJobs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = Server().__enter__()

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__(None, None, None)

    def test_run_on_texwarpd_gives_the_local_result(self):
        client = texwarp.Client(self.server.url)
        with Folder() as out, Folder() as local_out:
            seen = []
            result = client.run(sheet_job(), out, timeout=120, progress=lambda f, s: seen.append(s))
            self.assertEqual(result["state"], "succeeded")
            self.assertEqual(client.status(result["job_id"])["state"], "succeeded")
            self.assertEqual(seen[-1], "succeeded")
            uvs = LocalJobs.check_sheet_result(self, result, out)
            local = read_json(os.path.join(texwarp.run_local(sheet_job(), local_out)["files"][0].rsplit("/", 1)[0],
                                           "uvs.json"))
            self.assertEqual(local["uv"], uvs["uv"])

    def test_submit_poll_fetch_with_an_uploaded_texture(self):
        client = texwarp.Client(self.server.url)
        blob = client.upload_file(os.path.join(SOURCE_DIR, "examples", "astronaut.png"))
        self.assertTrue(blob.startswith("sha256:"))
        job = {"image": {"blob": blob}, "warp": {"features": [{"source": [100, 100], "target": [110, 95]},
                                                              {"source": [300, 300], "target": [290, 310]}]},
               "output": {"width": 128, "height": 128}}
        handle = client.submit(job)
        self.assertIn(handle.state, ("queued", "running", "succeeded"))
        deadline = time.monotonic() + 120
        while not handle.poll():
            self.assertLess(time.monotonic(), deadline)
            time.sleep(0.01)
        self.assertEqual(handle.state, "succeeded")
        self.assertEqual(handle.progress, 1.0)
        with Folder() as out:
            result = handle.fetch(out)
            self.assertEqual(sorted(os.path.basename(f) for f in result["files"]), ["report.json", "warped.png"])
            report = result["report"]
            self.assertEqual((report["kind"], report["output"]["width"], report["output"]["height"]),
                             ("image", 128, 128))
            self.assertLess(report["residuals"]["max_px"], 0.05)

    def test_a_refused_job_raises_problem_error_with_the_servers_path(self):
        client = texwarp.Client(self.server.url)
        job = sheet_job()
        job["mesh"]["features"]["features"][1]["source"] = "left"
        with self.assertRaises(texwarp.ProblemError) as raised:
            client.submit(job)
        e = raised.exception
        self.assertEqual((e.status, e.type), (422, "urn:texwarp:problem:invalid-job"))
        self.assertEqual(e.path, "$.mesh.features.features[1].source")
        self.assertNotIsInstance(e, texwarp.InputError)

    def test_a_job_that_fails_on_the_server_raises_job_failed_error(self):
        client = texwarp.Client(self.server.url)
        with Folder() as folder:
            obj = os.path.join(folder, "broken.obj")
            with open(obj, "w") as f:
                f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
            image = client.upload_file(os.path.join(SOURCE_DIR, "examples", "astronaut.png"))
            job = broken_mesh_job({"blob": client.upload_file(obj), "format": "obj"})
            job["image"] = {"blob": image}
            handle = client.submit(job)
            with self.assertRaises(texwarp.JobFailedError) as raised:
                handle.wait(timeout=120)
            e = raised.exception
            self.assertEqual((e.type, e.path), ("urn:texwarp:problem:invalid-job", "$.mesh.source"))
            self.assertIn("vertex 7", e.detail)
            self.assertEqual(handle.state, "failed")
            with self.assertRaises(texwarp.JobFailedError):
                handle.fetch(folder)

    def test_no_server_is_a_connection_problem(self):
        client = texwarp.Client("http://127.0.0.1:1", retry_budget=0)
        with self.assertRaises(texwarp.ProblemError) as raised:
            client.run(sheet_job(), tempfile.gettempdir())
        self.assertEqual(raised.exception.type, "urn:texwarp:client:connection")
        self.assertEqual(raised.exception.status, 0)


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


PNG_COLOR_TYPES = {1: 0, 2: 4, 3: 2, 4: 6}  # channels → PNG colour type (grey, grey + alpha, RGB, RGBA)


def write_png(path, array):
    """A uint8 or uint16 H×W or H×W×C array as a PNG (no filter), written here without texwarp."""
    h, w = array.shape[:2]
    c = 1 if array.ndim == 2 else array.shape[2]
    depth = 16 if array.dtype == np.uint16 else 8
    rows = array.astype(">u2" if depth == 16 else np.uint8).reshape(h, -1)
    raw = b"".join(b"\0" + row.tobytes() for row in rows)
    with open(path, "wb") as f:
        header = struct.pack(">IIBBBBB", w, h, depth, PNG_COLOR_TYPES[c], 0, 0, 0)
        f.write(b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", header) + png_chunk(b"IDAT", zlib.compress(raw))
                + png_chunk(b"IEND", b""))


def read_png(path):
    """A non-interlaced 8/16-bit grey/RGB(A) PNG as an H×W×C array (every filter type undone)."""
    with open(path, "rb") as f:
        data = f.read()
    pos, idat = 8, b""
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            w, h, depth, color_type, _, _, interlace = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    assert interlace == 0
    c = {v: k for k, v in PNG_COLOR_TYPES.items()}[color_type]
    bpp = c * depth // 8
    stride = w * bpp
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(h, stride + 1)
    out = np.zeros((h, stride), np.int32)
    for y in range(h):
        kind, row = raw[y, 0], raw[y, 1:].astype(np.int32)
        up = out[y - 1] if y > 0 else np.zeros(stride, np.int32)
        if kind == 0:
            out[y] = row
        elif kind == 2:
            out[y] = (row + up) & 0xFF
        else:  # Sub, Average, Paeth: byte by byte
            for x in range(stride):
                left = out[y, x - bpp] if x >= bpp else 0
                upleft = up[x - bpp] if x >= bpp else 0
                if kind == 1:
                    pred = left
                elif kind == 3:
                    pred = (left + up[x]) // 2
                else:
                    p = left + up[x] - upleft
                    pa, pb, pc = abs(p - left), abs(p - up[x]), abs(p - upleft)
                    pred = left if pa <= pb and pa <= pc else up[x] if pb <= pc else upleft
                out[y, x] = (row[x] + pred) & 0xFF
    samples = out.astype(np.uint8).tobytes()
    array = np.frombuffer(samples, ">u2" if depth == 16 else np.uint8).astype(np.uint16 if depth == 16 else np.uint8)
    return array.reshape(h, w, c)


def test_image(h, w, c, dtype, seed):
    """Smooth colour with some noise, an alpha channel (when C is 2 or 4) with transparent and partial pixels."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:h, 0:w].astype(np.float64)
    planes = [0.5 + 0.4 * np.sin(x / (5.0 + k) + y / (7.0 + 2 * k) + k) for k in range(c)]
    image = np.clip(np.stack(planes, axis=-1) + rng.normal(0, 0.03, (h, w, c)), 0, 1)
    if c in (2, 4):
        image[..., -1] = np.clip((x + y) / (w + h) * 1.4 - 0.2, 0, 1)
    if dtype == np.float32:
        return image.astype(np.float32)
    top = np.iinfo(dtype).max
    return np.rint(image * top).astype(dtype)


# A warp that moves and turns the texture's middle while its corners stay: a field, not a closed form.
SWIRL = {"features": [{"source": [8, 8], "target": [8, 8]}, {"source": [88, 8], "target": [88, 8]},
                      {"source": [8, 88], "target": [8, 88]}, {"source": [88, 88], "target": [88, 88]},
                      {"source": [48, 48], "target": [54, 44]}, {"source": [30, 60], "target": [26, 66]}]}
# Sources (4, 4), (28, 4), (4, 28) to twice themselves: the pre-alignment S(z) = 2z is the whole map.
DOUBLING = [{"source": [4, 4], "target": [8, 8]}, {"source": [28, 4], "target": [56, 8]},
            {"source": [4, 28], "target": [8, 56]}]


class ArraysInMemory(unittest.TestCase):
    def run_job_on_png(self, folder, array, image_extra=None, output_extra=None):
        png = os.path.join(folder, "in.png")
        write_png(png, array)
        job = {"image": dict({"path": png}, **(image_extra or {})), "warp": SWIRL,
               "output": dict(output_extra or {}), "options": {"device": "cpu"}}
        out = os.path.join(folder, "out")
        result = texwarp.run_local(job, out)
        warped = [f for f in result["files"] if f.endswith(".png")]
        return read_png(warped[0])

    def test_uint8_rgb_and_rgba_equal_the_job_on_the_same_png(self):
        for channels in (3, 4):
            with self.subTest(channels=channels), Folder() as folder:
                array = test_image(96, 96, channels, np.uint8, seed=channels)
                from_file = self.run_job_on_png(folder, array)
                warped = texwarp.warp(array, SWIRL, backend="cpu")
                self.assertEqual(warped.dtype, np.uint8)
                self.assertEqual(warped.shape, (96, 96, 4))  # RGB gains coverage alpha (transparent border)
                self.assertEqual(from_file.shape, warped.shape)
                differing = np.count_nonzero(warped != from_file)
                self.assertEqual(differing, 0, f"{differing} samples differ, the largest by "
                                 f"{np.abs(warped.astype(int) - from_file.astype(int)).max()}")
                # Not the identity: the middle moved.
                self.assertGreater(np.abs(warped[..., :3].astype(int) - array[..., :3].astype(int)).max(), 20)

    def test_float32_grey_equals_the_job_on_a_16_bit_png(self):
        with Folder() as folder:
            levels = test_image(96, 96, 1, np.uint16, seed=7)
            array = (levels.astype(np.float32) / np.float32(65535))[..., 0]  # exactly what the PNG decodes to
            from_file = self.run_job_on_png(folder, levels, {"role": "data"}, {"pixel_format": "uint16"})
            warped, report = texwarp.warp(array, SWIRL, backend="cpu", return_report=True)
            self.assertEqual((warped.dtype, warped.shape), (np.float32, (96, 96, 2)))  # grey + coverage
            self.assertEqual(report["sampling"]["role"], "data")
            self.assertFalse(report["closed_form"])
            self.assertLess(report["certificate"]["max_error_px_bound"], 0.05)
            expected = from_file.astype(np.float64) / 65535
            alpha = warped[..., 1]
            self.assertLessEqual(np.abs(alpha - expected[..., 1]).max(), 0.5 / 65535 + 1e-7)
            opaque_enough = alpha > 0.1  # 16-bit unassociation of faint pixels loses precision in the file
            self.assertGreater(np.count_nonzero(opaque_enough), 8000)
            self.assertLessEqual(np.abs(warped[..., 0] - expected[..., 0])[opaque_enough].max(), 1 / 255)

    def test_a_pure_scaling_gives_the_bilinear_interpolation_of_a_ramp(self):
        # S(z) = 2z: output pixel (i, j) samples the source at ((i + 0.5) / 2, (j + 0.5) / 2); bilinear
        # interpolation of a ramp f = 0.01·x + 0.02·y (pixel centres at i + 0.5) is the ramp itself.
        y, x = np.mgrid[0:32, 0:32] + 0.5
        ramp = (0.01 * x + 0.02 * y).astype(np.float32)
        warped, report = texwarp.warp(ramp, DOUBLING, width=64, height=64, border="clamp", role="data",
                                      return_report=True)
        self.assertTrue(report["closed_form"])
        self.assertEqual((warped.shape, warped.dtype), ((64, 64), np.float32))
        oy, ox = np.mgrid[0:64, 0:64] + 0.5
        expected = 0.01 * (ox / 2) + 0.02 * (oy / 2)
        inside = (ox / 2 >= 0.5) & (ox / 2 <= 31.5) & (oy / 2 >= 0.5) & (oy / 2 <= 31.5)
        self.assertLess(np.abs(warped - expected)[inside].max(), 2e-6)
        self.assertAlmostEqual(float(warped[63, 63]), 0.01 * 31.5 + 0.02 * 31.5, places=5)  # clamped at the edge

    def test_map_points_in_closed_form_and_as_the_command_line(self):
        points = np.array([[1.0, 2.0], [10.0, 20.0], [-3.5, 7.25]])
        np.testing.assert_allclose(texwarp.map_points(points, DOUBLING), 2 * points, atol=1e-9)
        np.testing.assert_allclose(texwarp.map_points(points, DOUBLING, inverse=True), points / 2, atol=1e-9)
        self.assertEqual(texwarp.map_points(np.zeros((0, 2)), DOUBLING).shape, (0, 2))
        grid = np.array([[x, y] for x in range(5, 96, 15) for y in range(5, 96, 15)], dtype=np.float64)
        with Folder() as folder:
            features_file, points_file = os.path.join(folder, "f.json"), os.path.join(folder, "p.json")
            with open(features_file, "w") as f:
                json.dump(SWIRL, f)
            with open(points_file, "w") as f:
                json.dump(grid.tolist(), f)
            for inverse in (False, True):
                command = [os.environ["TEXWARP_CLI"], "map", "--features", features_file, "--points", points_file,
                           "--backend", "cpu"] + (["--inverse"] if inverse else [])
                cli = np.array(json.loads(subprocess.run(command, check=True, capture_output=True).stdout))
                here = texwarp.map_points(grid, SWIRL["features"], inverse=inverse, backend="cpu")
                self.assertEqual(here.dtype, np.float64)
                np.testing.assert_allclose(here, cli, atol=1e-9)
                self.assertGreater(np.abs(here - grid).max(), 1.0)
        # The features' sources land on their targets (f) and back (f⁻¹).
        sources = np.array([f["source"] for f in SWIRL["features"]], dtype=np.float64)
        targets = np.array([f["target"] for f in SWIRL["features"]], dtype=np.float64)
        np.testing.assert_allclose(texwarp.map_points(sources, SWIRL, backend="cpu"), targets, atol=0.01)
        np.testing.assert_allclose(texwarp.map_points(targets, SWIRL, inverse=True, backend="cpu"), sources, atol=0.01)

    def test_the_default_backend_gives_the_cpu_reference(self):
        array = test_image(64, 64, 3, np.uint8, seed=3)
        default = texwarp.warp(array, SWIRL)
        cpu = texwarp.warp(array, SWIRL, backend="cpu")
        self.assertLessEqual(np.abs(default.astype(int) - cpu.astype(int)).max(), 1)

    def test_the_gil_is_released_while_it_warps(self):
        array = test_image(1024, 1024, 3, np.uint8, seed=5)
        counted = [0]
        stop = threading.Event()

        def count():
            while not stop.is_set():
                counted[0] += 1

        counter = threading.Thread(target=count)
        counter.start()
        try:
            time.sleep(0.05)
            before = counted[0]
            start = time.monotonic()
            texwarp.warp(array, SWIRL, backend="cpu", threads=1, exact=True, width=512, height=512)
            seconds = time.monotonic() - start
            during = counted[0] - before
        finally:
            stop.set()
            counter.join()
        # Held throughout, the counter would not run at all during the call (a handful of switches at most).
        self.assertGreater(seconds, 0.1)
        self.assertGreater(during, 20000 * seconds, f"{during} iterations in {seconds:.2f} s")

    def test_shapes_and_dtypes_round_trip(self):
        features = {"features": []}  # the identity
        for dtype in (np.uint8, np.uint16, np.float16, np.float32, np.float64):
            for shape in ((5, 7), (5, 7, 1), (5, 7, 2), (5, 7, 3), (5, 7, 4)):
                with self.subTest(dtype=dtype, shape=shape):
                    channels = 1 if len(shape) == 2 else shape[2]
                    base = test_image(5, 7, channels, np.uint8, seed=channels).reshape(shape)
                    if dtype == np.uint8:
                        array = base
                    elif dtype == np.uint16:
                        array = base.astype(np.uint16) * 257  # 8-bit codes at 16 bits
                    else:
                        array = (base / 255).astype(dtype)
                    out = texwarp.warp(array, features, border="clamp", backend="cpu")
                    expect_dtype = array.dtype if array.dtype in (np.uint8, np.uint16) else np.float32
                    self.assertEqual((out.dtype, out.shape), (expect_dtype, shape))
                    if channels in (1, 3):  # no alpha: the identity gives every value back
                        if out.dtype == np.float32:
                            np.testing.assert_allclose(out, array.astype(np.float32), atol=2e-6)
                        else:
                            np.testing.assert_array_equal(out, array)
                    transparent = texwarp.warp(array, features, backend="cpu")
                    gained = 1 if channels in (1, 3) else 0
                    self.assertEqual(transparent.shape, shape[:2] + (channels + gained,))

    def test_bad_inputs_raise_input_error_naming_the_argument(self):
        grey = np.zeros((8, 8), np.uint8)
        features = {"features": [{"source": [1, 1], "target": [1, 1]}, {"source": [5, 5], "target": [5, 5]},
                                 {"source": "left", "target": [3, 3]}]}
        cases = [
            (lambda: texwarp.warp(np.zeros((2, 3, 5), np.uint8), []), "image", "got shape (2, 3, 5)"),
            (lambda: texwarp.warp(np.zeros(4, np.uint8), []), "image", "got shape (4,)"),
            (lambda: texwarp.warp(np.zeros((4, 4), np.int32), []), "image", "dtype int32 is not supported"),
            (lambda: texwarp.warp(np.full((4, 4), np.nan, np.float32), []), "image", "not finite"),
            (lambda: texwarp.warp(grey, features), "features: $.features[2].source", ""),
            (lambda: texwarp.warp(grey, {"features": [], "colour": 1}), "features: $.colour", ""),
            (lambda: texwarp.warp(grey, [], backend="vulkan"), "backend", ""),
            (lambda: texwarp.warp(grey, [], role="normal"), "role", ""),
            (lambda: texwarp.warp(grey, [], border="mirror"), "border", ""),
            (lambda: texwarp.warp(grey, [], width=0), "width", "> 0"),
            (lambda: texwarp.warp(grey, [], alpha=-1.0), "alpha", "> 0"),
            (lambda: texwarp.map_points(np.zeros((3, 3)), []), "points", "got shape (3, 3)"),
            (lambda: texwarp.map_points([[0, 1], [2, float("inf")]], []), "points", "row 1"),
            (lambda: texwarp.map_points([[0, 1]], features, backend="cpu"), "features: $.features[2].source", ""),
        ]
        for call, path, detail in cases:
            with self.subTest(path=path, detail=detail):
                with self.assertRaises(texwarp.InputError) as raised:
                    call()
                self.assertEqual(raised.exception.path, path)
                self.assertIn(detail, raised.exception.detail)
                self.assertEqual(str(raised.exception), f"{path}: {raised.exception.detail}")
        with self.assertRaises(TypeError):
            texwarp.warp(grey, [], "bilinear")  # options are keyword-only


class TypeStubs(unittest.TestCase):
    STUBS = os.path.join(os.path.dirname(texwarp.__file__), "_texwarp.pyi")

    def test_the_stubs_are_installed_with_the_marker_and_name_what_the_module_has(self):
        folder = os.path.dirname(texwarp.__file__)
        for name in ("__init__.pyi", "_texwarp.pyi", "py.typed"):
            self.assertTrue(os.path.isfile(os.path.join(folder, name)), name)
        with open(os.path.join(folder, "__init__.pyi")) as f:
            package = ast.parse(f.read())
        exported = next(n for n in package.body if isinstance(n, ast.Assign) and n.targets[0].id == "__all__")
        names = [e.value for e in exported.value.elts]
        self.assertEqual(sorted(names), sorted(texwarp.__all__))
        for name in names:
            self.assertTrue(hasattr(texwarp, name), name)

    def test_the_stubs_parameters_are_the_extensions(self):
        # pybind11's docstrings begin with each signature: the stub's parameter names must be the same, in order.
        with open(self.STUBS) as f:
            stubs = ast.parse(f.read())
        functions = {}
        for node in stubs.body:
            if isinstance(node, ast.FunctionDef):
                functions[node.name] = node
        self.assertEqual(sorted(functions), ["map_points", "run_local", "submit_local", "warp"])
        for name, node in functions.items():
            a = node.args
            stub = [p.arg for p in a.posonlyargs + a.args] + ["*"] * bool(a.kwonlyargs) + [p.arg for p in a.kwonlyargs]
            signature = getattr(texwarp._texwarp, name).__doc__.split("\n")[0]
            inner = signature[signature.index("(") + 1:signature.rindex(") ->")]
            runtime = [p.split(":")[0].strip() for p in inner.split(", ") if p.split(":")[0].strip().isidentifier()
                       or p.strip() == "*"]
            self.assertEqual(stub, runtime, signature)

    @unittest.skipUnless(shutil.which("mypy") or os.path.exists("/usr/lib/python3/dist-packages/mypy"),
                         "mypy is not installed (apt-get install python3-mypy)")
    def test_mypy_accepts_a_program_using_the_api_and_refuses_a_wrong_one(self):
        good = '''import numpy as np
import numpy.typing as npt
import texwarp

image: npt.NDArray[np.uint8] = np.zeros((4, 4, 3), np.uint8)
warped: npt.NDArray[np.uint8] = texwarp.warp(image, {"features": []}, width=8, border="clamp")
pair = texwarp.warp(np.zeros((4, 4), np.float32), [], return_report=True)
grey: npt.NDArray[np.float32] = pair[0]
halves: npt.NDArray[np.float32] = texwarp.warp(np.zeros((4, 4), np.float16), [])
points: npt.NDArray[np.float64] = texwarp.map_points([[1.0, 2.0]], [], inverse=True)
job: texwarp.Job = texwarp.submit_local({"image": {"path": "a.png"}})
state: str = job.wait(timeout=1.0)
try:
    texwarp.run_local({}, "out")
except texwarp.InputError as e:
    print(e.path, e.detail, texwarp.__version__, texwarp.Client("http://h").server_url)
'''
        bad = '''import numpy as np
import numpy.typing as npt
import texwarp

wrong: npt.NDArray[np.uint8] = texwarp.map_points([[1.0, 2.0]], [], inverse=1.5)
texwarp.warp(np.zeros((4, 4), np.uint8), [], border="mirror")
'''
        site = os.path.dirname(os.path.dirname(os.path.realpath(texwarp.__file__)))  # where the package is installed: its
        # stubs and errors.py are checked strictly too (found through MYPYPATH, not as an installed package)
        with Folder() as folder:
            results = []
            for name, text in (("good.py", good), ("bad.py", bad)):
                with open(os.path.join(folder, name), "w") as f:
                    f.write(text)
                results.append(subprocess.run(
                    ["/usr/bin/python3", "-m", "mypy", "--strict", "--no-incremental", "--cache-dir", os.devnull,
                     name], cwd=folder, capture_output=True, text=True,
                    env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"} | {"MYPYPATH": site}))
            good_run, bad_run = results
            self.assertEqual(good_run.returncode, 0, good_run.stdout + good_run.stderr)
            self.assertEqual(bad_run.returncode, 1, bad_run.stdout + bad_run.stderr)
            self.assertIn("bad.py:5: error", bad_run.stdout)
            self.assertIn("bad.py:6: error", bad_run.stdout)


if __name__ == "__main__":
    unittest.main(verbosity=2)
