"""A stand-in for ``blender -c ID ARGS...`` built on the bpy module (no Blender program here).

As Blender does for ``-c``: the commands registered with ``bpy.utils.register_cli_command``
while ``sh_lighting.register()`` runs are recorded (the real function still called), and ID's
``execute`` is called with the arguments after it; its return value is the exit status (an
unknown ID: a message and status 1). Understands ``[-b] -c ID ARGS...`` only.

With BLENDER_STAND_IN_STALL_AFTER_FRAME=N it sleeps right after writing a frame after N,
before the move: where a kill leaves a hidden temporary frame, every time.

Usage: PYTHONPATH=<repository> python blender_stand_in.py [-b] (-c|--command) ID ARGS...
"""

import os
import sys
import time


def main(argv):
    args = list(argv)
    while args and args[0] in ("-b", "--background"):
        args.pop(0)
    if len(args) < 2 or args[0] not in ("-c", "--command"):
        print(f"blender stand-in: expected [-b] -c ID ARGS..., got {argv}", file=sys.stderr)
        return 2
    command, rest = args[1], args[2:]

    import bpy

    stall_after = os.environ.get("BLENDER_STAND_IN_STALL_AFTER_FRAME")
    if stall_after:  # a test's: a Blender that hangs once a frame's file is written
        @bpy.app.handlers.persistent  # kept when the command opens its .blend
        def stall(scene, *_):
            if scene.frame_current > int(stall_after):
                time.sleep(600)

        bpy.app.handlers.render_write.append(stall)

    registered = {}
    real_register = bpy.utils.register_cli_command

    def recording_register(identifier, execute):
        registered[identifier] = execute
        return real_register(identifier, execute)

    bpy.utils.register_cli_command = recording_register
    try:
        import sh_lighting

        sh_lighting.register()
    finally:
        bpy.utils.register_cli_command = real_register
    if command not in registered:
        print(f"Unrecognized command: '{command}'", file=sys.stderr)
        return 1
    return registered[command](rest)


if __name__ == "__main__":
    status = main(sys.argv[1:])
    # Leave without interpreter shutdown, where the bpy 4.2 module (not Blender) crashes once
    # an add-on registered properties with Python callbacks (see tests/conftest.py).
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)
