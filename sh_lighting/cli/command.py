"""``blender -c sh_lighting compute|apply|render|batch ...``: the command line inside Blender.

Blender 4.2+ runs a command registered with ``bpy.utils.register_cli_command(id, execute)``
when started as ``blender -c ID ARGS...`` (``--command``; implies background mode): after the
enabled add-ons and extensions are registered, ``execute`` gets the arguments that follow the
id and its return value is Blender's exit status. Registering ``sh_lighting`` here, in the
extension's register(), makes the installed extension's command line available without a
path to ``cli/script.py``. The handle is kept to unregister it; a second registration of the same id
would make Blender refuse both ("registered duplicate command").
"""

import bpy

COMMAND = "sh_lighting"
classes = ()  # no Blender classes: the command is registered by its id

# Blender returns a handle from register_cli_command and needs it back to unregister: the
# module holds it from register() to unregister() (empty otherwise).
_handles = []


def execute(argv):
    """The command's callback: ``cli.run_blender_command`` on the arguments after the id."""
    from .. import cli

    return cli.run_blender_command(argv)


def register():
    _handles.append(bpy.utils.register_cli_command(COMMAND, execute))


def unregister():
    while _handles:
        bpy.utils.unregister_cli_command(_handles.pop())
