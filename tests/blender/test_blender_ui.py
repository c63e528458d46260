"""The add-on from Blender's UI, in a real window (Xvfb): invoked from the UI the operator runs modal (its job on a
thread, Blender's event loop keeps running: timer ticks counted while the job runs), the UVs arrive, Ctrl-Z (ed.undo)
restores them, and Esc (a simulated key press, --enable-event-simulate) cancels a long job and leaves the UVs as
they were. On a real texwarpd (the preferences' URL) the operator returns before the job has ended (upload, submit,
wait and fetch on the add-on's thread), the UI keeps ticking while the server works, and the UVs are applied once
the server says the job succeeded. Then two runs that must end with a message, never stuck or with a traceback: the
object deleted while its texture uploads (the worker thread reads no bpy), and an unexpected error (not texwarp's,
injected) in the worker thread; neither leaves its scratch folder. Environment as test_blender_addon.py. Exits 1 on
failure."""

import os
import shutil
import sys
import tempfile
import threading
import time
import traceback

import datetime
import json
import urllib.request

import bmesh
import bpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from test_blender_addon import (FAILURES, bent_grid, check, edit, install_addon, start_texwarpd,  # noqa: E402
                                texture)

state = {"phase": "start"}


def ui_context():
    win = bpy.context.window_manager.windows[0]
    area = max(win.screen.areas, key=lambda a: a.width * a.height)
    area.type = "IMAGE_EDITOR"
    area.spaces.active.image = bpy.data.images["features"]  # drawing the 4096² one would take seconds on Xvfb
    region = [r for r in area.regions if r.type == "WINDOW"][0]
    return dict(window=win, area=area, region=region, screen=win.screen)


def loop_uvs():
    bm = bmesh.from_edit_mesh(bpy.context.object.data)
    layer = bm.loops.layers.uv.active
    return [tuple(loop[layer].uv) for f in bm.faces for loop in f.loops]


def differing(a, b):
    return sum(1 for p, q in zip(a, b) if p != q)


def invoke(image):
    with bpy.context.temp_override(**ui_context()):
        bpy.ops.ed.undo_push(message="before texwarp")
        return bpy.ops.uv.texwarp_constrained_unwrap("INVOKE_DEFAULT", image_name=image)


def server_jobs(url):
    """The jobs texwarpd holds (GET /v1/jobs)."""
    with urllib.request.urlopen(url + "/v1/jobs", timeout=10) as reply:
        return json.load(reply)["jobs"]


def server_time(text):
    """A texwarpd timestamp ("2026-12-01T07:21:44.430Z") in seconds since the epoch."""
    moment = datetime.datetime.strptime(text, "%Y-%m-%dT%H:%M:%S.%fZ")
    return moment.replace(tzinfo=datetime.timezone.utc).timestamp()


def info_reports():
    """The operators' reports so far (read from an Info editor through the clipboard)."""
    win = bpy.context.window_manager.windows[0]
    area = min(win.screen.areas, key=lambda a: a.width * a.height)
    area.type = "INFO"
    region = [r for r in area.regions if r.type == "WINDOW"][0]
    with bpy.context.temp_override(window=win, area=area, region=region, screen=win.screen):
        bpy.ops.info.select_all(action="SELECT")
        bpy.ops.info.report_copy()
    return bpy.context.window_manager.clipboard


def scratch_folders():
    return {n for n in os.listdir(tempfile.gettempdir()) if n.startswith("texwarp-blender-")}


def addon_operator():
    return sys.modules["texwarp_blender.operator"]


def failing_mesh_job(*args, **kwargs):
    raise RuntimeError("injected failure")


THREAD_ERRORS = []  # exceptions that ended a thread (threading.excepthook): the add-on's threads must catch theirs


def record_thread_error(args):
    THREAD_ERRORS.append("%s: %s" % (args.exc_type.__name__, args.exc_value))
    traceback.print_exception(args.exc_type, args.exc_value, args.exc_traceback)


threading.excepthook = record_thread_error


def ended_with(text, what, now, limit_s):
    """Whether the running operator has ended with a report holding `text` (checked, with its scratch folder
    removed), or `limit_s` passed (a failure); False while it still runs."""
    s = state
    reports = info_reports()
    if text not in reports and now - s["t0"] < limit_s:
        return False
    check(text in reports, "%s ended within %d s with a message (reports: %r)" % (what, limit_s, reports[-300:]))
    check(not (scratch_folders() - s["scratch"]), "%s left no scratch folder" % what)
    return True


def stop_server():
    proc = state.get("server")
    if proc is not None:
        proc.terminate()
        proc.wait(timeout=30)


def step():
    s = state
    try:
        now = time.monotonic()
        if s["phase"] == "start":
            edit(bent_grid("ui", 24, (0.4, 0.4), {(7, 15): (-0.06, 0.0), (17, 15): (0.06, 0.0), (12, 7): (0.0, 0.04)}))
            s["before"] = loop_uvs()
            check(invoke("features") == {"RUNNING_MODAL"}, "from the UI the operator runs modal")
            s.update(phase="small", t0=now)
        elif s["phase"] == "small":
            if differing(loop_uvs(), s["before"]) == 0:
                check(now - s["t0"] < 120, "the small job ends within 120 s")
                if now - s["t0"] >= 120:
                    s["phase"] = "quit"
                return 0.05
            check(any(i.name == "features.texwarp" for i in bpy.data.images), "the warped image arrived")
            with bpy.context.temp_override(**ui_context()):
                bpy.ops.ed.undo()
            check(differing(loop_uvs(), s["before"]) == 0, "Ctrl-Z (ed.undo) restores the UVs")
            # A long job (a 4096² texture to warp): the event loop keeps ticking while it runs, then Esc cancels it.
            edit(bent_grid("big", 60, (0.4, 0.4), {(15, 40): (-0.06, 0.0), (45, 40): (0.06, 0.0),
                                                   (30, 15): (0.0, 0.04)}))
            s["before"] = loop_uvs()
            check(invoke("big") == {"RUNNING_MODAL"}, "the long job runs modal")
            s.update(phase="big", t0=time.monotonic(), ticks=[])  # after invoke (which writes the texture's PNG)
        elif s["phase"] == "big":
            s["ticks"].append(now - s["t0"])
            if now - s["t0"] < 3.0:
                return 0.1
            # Ticks asked every 0.1 s over 3 s: most of them come while the job runs (the UI is not blocked).
            check(len(s["ticks"]) >= 10, "%d event-loop ticks in 3 s while the job runs" % len(s["ticks"]))
            win = bpy.context.window_manager.windows[0]
            win.event_simulate(type="ESC", value="PRESS")
            win.event_simulate(type="ESC", value="RELEASE")
            s.update(phase="esc", t0=now)
            return 2.0
        elif s["phase"] == "esc":
            check(differing(loop_uvs(), s["before"]) == 0, "after Esc the UVs are as they were")
            # The operator said so (its report, read from an Info editor through the clipboard).
            reports = info_reports()
            check("texwarp: canceled" in reports, "Esc canceled the job (reports: %r)" % reports[-200:])
            # On a texwarpd: the 2048² texture is uploaded and warped there while the UI runs.
            proc, url = start_texwarpd(folder)
            s.update(server=proc, url=url)
            bpy.context.preferences.addons["texwarp_blender"].preferences.server_url = url
            edit(bent_grid("remote", 24, (0.4, 0.4), {(7, 15): (-0.06, 0.0), (17, 15): (0.06, 0.0),
                                                      (12, 7): (0.0, 0.04)}))
            s["before"] = loop_uvs()
            t0 = time.monotonic()
            check(invoke("mid") == {"RUNNING_MODAL"}, "on a texwarpd the operator runs modal")
            returned = time.monotonic()
            s["returned_at"] = time.time()
            jobs = server_jobs(url)
            check(not any(j["state"] == "succeeded" for j in jobs),
                  "the operator returned (%.2f s) before the job ended (server: %s)" %
                  (returned - t0, [j["state"] for j in jobs]))
            check(differing(loop_uvs(), s["before"]) == 0, "no UVs applied when the operator returns")
            s.update(phase="remote", t0=returned, ticks=[], seen=set(), created=None)
        elif s["phase"] == "remote":
            s["ticks"].append(now - s["t0"])
            jobs = server_jobs(s["url"])
            s["seen"].update(j["state"] for j in jobs)
            if jobs and s["created"] is None:
                s["created"] = server_time(jobs[0]["created_at"])
                # Upload and submit come after the operator returned (on its thread), not before.
                check(s["created"] > s["returned_at"], "the job was submitted %.3f s after the operator returned" %
                      (s["created"] - s["returned_at"]))
            if differing(loop_uvs(), s["before"]) == 0:
                if now - s["t0"] >= 300:
                    check(False, "the job on texwarpd ends within 300 s")
                    s["phase"] = "quit"
                return 0.05
            applied = time.time()
            check([j["state"] for j in jobs] == ["succeeded"], "UVs applied after the job succeeded: %s" % jobs)
            if jobs and jobs[0]["finished_at"]:
                check(server_time(jobs[0]["finished_at"]) <= applied, "the job ended %.3f s before the UVs came" %
                      (applied - server_time(jobs[0]["finished_at"])))
            check(bool(s["seen"] & {"queued", "running"}),
                  "the UI ran while the job was queued or running (states seen: %s)" % sorted(s["seen"]))
            check(len(s["ticks"]) >= 5, "%d event-loop ticks while the job ran on texwarpd" % len(s["ticks"]))
            check(any(i.name == "mid.texwarp" for i in bpy.data.images), "the warped image arrived from texwarpd")
            # The object deleted right after invoke, while its texture uploads: the job is made on the worker
            # thread from plain values (no bpy there), so the run goes on and ends with a message, not a stuck bar.
            obj = bent_grid("gone", 24, (0.4, 0.4), {(7, 15): (-0.06, 0.0), (17, 15): (0.06, 0.0),
                                                     (12, 7): (0.0, 0.04)})
            edit(obj)
            s["scratch"] = scratch_folders()
            check(invoke("mid") == {"RUNNING_MODAL"}, "the run whose object is deleted runs modal")
            bpy.ops.object.mode_set(mode="OBJECT")
            bpy.data.objects.remove(obj, do_unlink=True)
            s.update(phase="gone", t0=now)
        elif s["phase"] == "gone":
            if not ended_with("was deleted while texwarp ran", "the run whose object was deleted", now, 300):
                return 0.5
            # An unexpected error (not texwarp's) in the worker thread: the operator ends with it as its message.
            s["mesh_job"] = addon_operator().mesh_job.mesh_job
            addon_operator().mesh_job.mesh_job = failing_mesh_job
            edit(bent_grid("boom", 8, (0.4, 0.4), {(2, 5): (-0.06, 0.0), (6, 5): (0.06, 0.0)}))
            s["scratch"] = scratch_folders()
            check(invoke("mid") == {"RUNNING_MODAL"}, "the run whose worker fails runs modal")
            s.update(phase="boom", t0=now)
        elif s["phase"] == "boom":
            if not ended_with("unexpected error (RuntimeError: injected failure", "the run whose worker failed", now,
                              120):
                return 0.5
            addon_operator().mesh_job.mesh_job = s["mesh_job"]
            s["phase"] = "quit"
        else:
            stop_server()
            check(not THREAD_ERRORS, "no exception ended an add-on thread: %s" % THREAD_ERRORS)
            print("blender UI test: %d failure(s)" % len(FAILURES), flush=True)
            shutil.rmtree(folder, ignore_errors=True)
            os._exit(1 if FAILURES else 0)
    except Exception:
        traceback.print_exc()
        stop_server()
        shutil.rmtree(folder, ignore_errors=True)
        os._exit(1)
    return 0.05


install_addon()
folder = tempfile.mkdtemp(prefix="texwarp-blender-ui-")
texture(folder)
big = bpy.data.images.new("big", 4096, 4096)
big.generated_type = "COLOR_GRID"
mid = bpy.data.images.new("mid", 2048, 2048)
mid.generated_type = "COLOR_GRID"
bpy.app.timers.register(step, first_interval=1.0)
