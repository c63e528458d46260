"""The texwarp Python module as installed (PYTHONPATH at the install prefix's site-packages): local jobs (the runner
in-process), jobs on a real texwarpd on loopback (started here), errors as exceptions with the problem's path.
Environment: TEXWARP_PREFIX (the install prefix), TEXWARPD and TEXWARP_CLI (binaries), TEXWARP_SOURCE_DIR."""

import json
import os
import shutil
import subprocess
import tempfile
import time
import unittest

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


if __name__ == "__main__":
    unittest.main(verbosity=2)
