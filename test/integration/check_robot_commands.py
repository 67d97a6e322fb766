#!/usr/bin/env python3
"""Checks every command of docs/on_your_robot.md against the launch files and the code.

Commands are the lines of the page's fenced bash blocks (backslash continuations joined, comments
dropped) and its inline code spans that start with a ROS command (`roslaunch occupancy_fusion
...`, `rosrun`, `rosservice`, `rosparam`, `rostopic`). They are checked in the page's order, as a
user following the page runs them; `$HOME` is a temporary folder and `$(rospack find
occupancy_fusion)` the package root. Each kind of command has its check, and a command of a kind
without one fails (a page command nobody checks is not allowed):

- `roslaunch occupancy_fusion <file> name:=value ...`: the file is in launch/; every name is an
  `<arg>` the file declares (xml.etree), every arg it declares without a default is given, a
  boolean arg gets true or false, a file given to a `*_config` arg exists, `load_map` names a .ot
  or .bt file and `save_on_shutdown` a prefix in an existing folder; `:=~` is refused (bash does
  not expand ~ there). Where `roslaunch` is on PATH, also `roslaunch --dump-params` with the same
  arguments, which parses the launch and loads its parameter files (it fails on a bad value or a
  missing file), and the map parameters of its nodelets (map_name, frame_id, resolution,
  max_memory_mb, block_storage) must agree, as the nodelets of one map require; skipped with a
  note otherwise.
- `rosservice call /<node>/<service> "<request>"`: the node is a node of launch/mapping.launch,
  the service is advertised in src/ or include/, and the request's fields are its .srv's.
- `rosparam get|set /<node>/<name>`: the node is in mapping.launch and the parameter is read in
  code (as check_parameters_documented.py extracts them, or a string literal of the sources) or
  set in the launch file;
  `use_sim_time` is ROS's own.
- `rostopic echo|hz|info [-n N] <topic>` and `rostopic list`: the topic is published by the code
  (`/diagnostics` through diagnostic_updater) or one the page's roslaunch lines map.
- `rosrun <package> <executable> ...`: for this package an executable target of CMakeLists.txt;
  for others, where ROS is installed, the executable is found as rosrun finds it (`catkin_find
  --libexec`, the package folder); `static_transform_publisher` gets x y z yaw pitch roll (or a
  quaternion) and two frames, `tf2_tools echo.py` two frames, frames without a leading slash.
- `rviz -d <file>`: the file exists.
- `cp`, `mkdir -p`, `sed -i`: run in the temporary folder (never on the package); a `sed -i
  's/^key: .../.../'` must change that key in every target file that holds it.

Usage: check_robot_commands.py <package root> [--junit FILE.xml]; prints each command with its
line and result, exits 1 if any fails. With --junit it also writes JUnit XML (as the gtests do,
into catkin's test_results folder, where scripts/count_test_results.py counts it): one test case
per command, one per roslaunch --dump-params check (skipped without roslaunch), and one that fails
when the extraction finds no roslaunch line.
"""
import glob
import importlib.util
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ElementTree

import junit_report  # beside this script

PAGE = "docs/on_your_robot.md"
PACKAGE = "occupancy_fusion"
ROS_COMMANDS = ("roslaunch", "rosrun", "rosservice", "rosparam", "rostopic")
FENCE = re.compile(r"^ {0,3}(`{3,}|~{3,})\s*([\w+-]*)")
SHELL_LANGUAGES = {"bash", "sh", "shell", "console"}
CODE_SPAN = re.compile(r"(`+)([^`].*?)\1")
# The map parameters every nodelet of one map must give alike.
MAP_PARAMETERS = ("map_name", "frame_id", "resolution", "max_memory_mb", "block_storage")
GLOBAL_PARAMETERS = {"use_sim_time"}


class Command:
    def __init__(self, line, text):
        self.line = line
        self.text = text
        self.problems = []
        self.notes = []
        self.ros_check = None  # (problems, notes) of roslaunch --dump-params, or a skip note


def extract_commands(text):
    """Command lines of the page's shell blocks and its inline ROS command spans, in order."""
    commands = []
    lines = text.splitlines()
    index = 0
    while index < len(lines):
        fence = FENCE.match(lines[index])
        if not fence:
            for span in CODE_SPAN.finditer(lines[index]):
                words = span.group(2).split()
                if len(words) >= 2 and words[0] in ROS_COMMANDS:
                    commands.append(Command(index + 1, span.group(2).strip()))
            index += 1
            continue
        marker, language = fence.group(1), fence.group(2).lower()
        index += 1
        pending, start = "", None
        while index < len(lines) and not lines[index].strip().startswith(marker):
            line = lines[index]
            if language in SHELL_LANGUAGES:
                if start is None:
                    start = index + 1
                if line.rstrip().endswith("\\"):
                    pending += line.strip()[:-1].strip() + " "
                else:
                    whole = (pending + line.strip()).strip()
                    if whole and not whole.startswith("#"):
                        commands.append(Command(start, whole))
                    pending, start = "", None
            index += 1
        index += 1  # the closing fence
    return commands


class Page:
    """What the checks know: the package, the sandbox standing for $HOME, the launch files."""

    def __init__(self, root, sandbox):
        self.root = root
        self.sandbox = sandbox
        self.mapped_topics = set()  # topic values of the page's roslaunch lines
        self.sources = []
        for pattern in ("src/**/*.cpp", "src/**/*.h", "include/**/*.h"):
            self.sources += sorted(root.glob(pattern))
        self.code = "\n".join(path.read_text(encoding="utf-8", errors="replace")
                              for path in self.sources)

    # --- expansion, as bash would do it for the page's commands
    def words(self, command):
        text = command.text
        if re.search(r":=~", text):
            command.problems.append("':=~' is not expanded by bash: write $HOME")
        text = text.replace(f"$(rospack find {PACKAGE})", str(self.root))
        text = re.sub(r"\$\{HOME\}|\$HOME\b", str(self.sandbox), text)
        if re.search(r"\$\(|`|\$\{?[A-Za-z_]", text):
            command.problems.append("holds a substitution this check cannot expand")
        try:
            words = shlex.split(text, comments=True)
        except ValueError as error:
            command.problems.append(f"cannot be split as bash would: {error}")
            return []
        words = [str(self.sandbox) + word[1:] if word == "~" or word.startswith("~/") else word
                 for word in words]
        if words and words[-1] == "&":
            words = words[:-1]
        return words

    def inside(self, path, folder):
        try:
            pathlib.Path(path).resolve().relative_to(folder.resolve())
            return True
        except ValueError:
            return False

    # --- launch files
    def launch_file(self, name):
        path = self.root / "launch" / name
        return path if path.is_file() and path.parent == self.root / "launch" else None

    @staticmethod
    def declared_args(path):
        """{name: default or None} of the args a launch file declares (not those it passes to
        an include)."""
        tree = ElementTree.parse(path)
        declared = {}
        parents = {child: parent for parent in tree.iter() for child in parent}
        for arg in tree.iter("arg"):
            if parents.get(arg) is not None and parents[arg].tag == "include":
                continue
            declared[arg.get("name")] = arg.get("default", arg.get("value"))
        return declared

    def launch_nodes(self, name="mapping.launch"):
        tree = ElementTree.parse(self.root / "launch" / name)
        return {node.get("name") for node in tree.iter("node") if node.get("name")}

    def node_parameters(self, node_name, launch="mapping.launch"):
        """Parameters a launch file sets on a node with <param>."""
        tree = ElementTree.parse(self.root / "launch" / launch)
        for node in tree.iter("node"):
            if node.get("name") == node_name:
                return {param.get("name") for param in node.iter("param")}
        return set()


def check_roslaunch(page, command, words):
    if len(words) < 3:
        command.problems.append("roslaunch needs a package and a launch file")
        return None
    package, name, arguments = words[1], words[2], words[3:]
    if package != PACKAGE:
        command.problems.append(f"package '{package}' is not {PACKAGE}")
        return None
    path = page.launch_file(name)
    if path is None:
        command.problems.append(f"no launch file launch/{name}")
        return None
    declared = page.declared_args(path)
    given = {}
    for argument in arguments:
        if argument.startswith("-"):
            command.problems.append(f"option '{argument}' is not checked here: leave it off")
            continue
        arg_name, separator, value = argument.partition(":=")
        if not separator:
            command.problems.append(f"'{argument}' is not name:=value")
            continue
        if arg_name not in declared:
            command.problems.append(f"{name} declares no arg '{arg_name}'")
            continue
        given[arg_name] = value
        default = declared[arg_name]
        if default in ("true", "false") and value.lower() not in ("true", "false"):
            command.problems.append(f"{arg_name}:={value}: a boolean arg takes true or false")
        if arg_name.endswith("_config") and not pathlib.Path(value).is_file():
            command.problems.append(f"{arg_name}: no file {value}")
        if arg_name == "load_map" and not value.endswith((".ot", ".bt")):
            command.problems.append(f"load_map:={value}: the MapServer resumes a .ot or .bt file")
        if arg_name == "save_on_shutdown" and value and not pathlib.Path(value).parent.is_dir():
            command.problems.append(f"save_on_shutdown:={value}: its folder does not exist "
                                    "when the page gets here")
        if value.startswith("/") and not value.endswith((".yaml", ".ot", ".bt")) \
                and not page.inside(value, page.sandbox):
            page.mapped_topics.add(value)
    for arg_name, default in declared.items():
        if default is None and arg_name not in given:
            command.problems.append(f"{name} requires arg '{arg_name}'")
    command.notes.append(f"{len(given)} args declared in launch/{name}")
    return path


def ros_environment(page):
    environment = dict(os.environ)
    environment["HOME"] = str(page.sandbox)
    environment["ROS_HOME"] = str(page.sandbox / ".ros")
    environment["ROS_LOG_DIR"] = str(page.sandbox / ".ros" / "log")
    environment.setdefault("ROS_HOSTNAME", "localhost")
    # The package itself, where the environment does not have it yet (a plain shell).
    package_path = environment.get("ROS_PACKAGE_PATH", "")
    if str(page.root) not in package_path.split(":"):
        environment["ROS_PACKAGE_PATH"] = ":".join(p for p in (str(page.root), package_path) if p)
    return environment


def dump_params(page, words, roslaunch):
    """roslaunch --dump-params with the command's arguments: (problems, notes)."""
    completed = subprocess.run([roslaunch, "--dump-params"] + words[1:], cwd=page.sandbox,
                               env=ros_environment(page), capture_output=True, text=True,
                               timeout=120)
    output = completed.stdout + completed.stderr
    problems = []
    if completed.returncode != 0:
        problems.append(f"roslaunch --dump-params exits {completed.returncode}: "
                        + " ".join(output.split())[-400:])
    for marker in ("Unable to load file", "RLException", "ResourceNotFound", "Invalid <"):
        if marker in output:
            problems.append(f"roslaunch --dump-params: {' '.join(output.split())[:400]}")
            break
    parameters = {}
    for line in completed.stdout.splitlines():
        match = re.match(r"^(/[^:\s]+):\s?(.*)$", line)
        if match:
            parameters[match.group(1)] = match.group(2).strip()
    for key in MAP_PARAMETERS:
        values = {name.rsplit("/", 1)[0]: value for name, value in parameters.items()
                  if name.count("/") == 2 and name.endswith("/" + key)}
        if len(set(values.values())) > 1:
            problems.append(f"the nodelets disagree on map parameter {key}: " +
                            ", ".join(f"{node} {value}" for node, value in sorted(values.items())))
    nodes = sorted({name.split("/")[1] for name in parameters if name.count("/") >= 2})
    resolution = sorted({value for name, value in parameters.items()
                         if name.count("/") == 2 and name.endswith("/resolution")})
    notes = [f"roslaunch --dump-params: {len(parameters)} parameters of {', '.join(nodes)}; "
             f"resolution {', '.join(resolution)}"] if parameters else []
    return problems, notes, parameters


def service_fields(page, service):
    """The request fields of a service advertised in the code, or None when not advertised."""
    advertised = re.search(r'advertiseService\(\s*"' + re.escape(service) +
                           r'"\s*,\s*&(\w+)::(\w+)', page.code)
    if not advertised:
        return None
    handler = advertised.group(2)
    signature = re.search(r"\b" + re.escape(handler) + r"\(\s*([\w:]+)::Request", page.code)
    if not signature:
        return set()
    srv = page.root / "srv" / (signature.group(1).split("::")[-1] + ".srv")
    if not srv.is_file():
        return set()  # std_srvs::Empty and the like: no fields to give
    request = srv.read_text().split("---")[0]
    return {line.split()[1] for line in request.splitlines()
            if line.strip() and not line.strip().startswith("#") and len(line.split()) >= 2}


def check_rosservice(page, command, words):
    if len(words) < 3 or words[1] != "call":
        command.problems.append("only 'rosservice call /<node>/<service> ...' is checked")
        return
    node, _, service = words[2].lstrip("/").partition("/")
    if node not in page.launch_nodes():
        command.problems.append(f"no node '{node}' in launch/mapping.launch")
    fields = service_fields(page, service)
    if fields is None:
        command.problems.append(f"no service '{service}' advertised in the code")
        return
    request = " ".join(words[3:])
    given = set(re.findall(r"(\w+)\s*:", request))
    unknown = given - fields
    if unknown:
        command.problems.append(f"{service} has no request field(s) {sorted(unknown)}")
    if service == "save_map":
        prefix = re.search(r"prefix\s*:\s*'?([^'\s}]+)", request)
        if prefix and prefix.group(1).startswith("/") \
                and not pathlib.Path(prefix.group(1)).parent.is_dir():
            command.problems.append(f"save_map prefix {prefix.group(1)}: its folder does not "
                                    "exist when the page gets here")
    command.notes.append(f"/{node}/{service} advertised, request fields {sorted(fields)}")


def parameters_read_in_code(root):
    """The keys check_parameters_documented.py finds read in the code."""
    path = pathlib.Path(__file__).resolve().parent / "check_parameters_documented.py"
    spec = importlib.util.spec_from_file_location("check_parameters_documented", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return set(module.keys_read(root))


def check_rosparam(page, command, words, last_dump):
    if len(words) < 3 or words[1] not in ("get", "set"):
        command.problems.append("only 'rosparam get|set <name>' is checked")
        return
    name = words[2]
    if name.lstrip("/") in GLOBAL_PARAMETERS:
        command.notes.append(f"{name}: a ROS parameter")
        return
    node, _, key = name.lstrip("/").partition("/")
    if node not in page.launch_nodes():
        command.problems.append(f"no node '{node}' in launch/mapping.launch")
    # Read in code: found by check_parameters_documented.py's extraction, or else a string
    # literal of the sources (a key passed as a default argument, "max_memory_mb").
    read = key in page.read_keys or f'"{key}"' in page.code
    if not read and key not in page.node_parameters(node):
        command.problems.append(f"'{key}' is neither read in the code nor set by the launch file")
    if last_dump is not None:
        value = last_dump.get("/" + name.lstrip("/"))
        if value is None:
            command.problems.append(f"{name} is not among the parameters of the page's "
                                    "roslaunch line before it")
        else:
            command.notes.append(f"{name} = {value} after the roslaunch line before it")


def check_rostopic(page, command, words):
    if len(words) >= 2 and words[1] == "list":
        return
    if len(words) < 3 or words[1] not in ("echo", "hz", "info"):
        command.problems.append("only 'rostopic echo|hz|info <topic>' and 'rostopic list' "
                                "are checked")
        return
    topic = [word for word in words[2:] if not word.startswith("-") and not word.isdigit()]
    if len(topic) != 1:
        command.problems.append("expected one topic")
        return
    topic = topic[0]
    base = topic.rstrip("/").rsplit("/", 1)[-1]
    if topic == "/diagnostics":
        if "diagnostic_updater::Updater" not in page.code:
            command.problems.append("no diagnostic_updater in the code: nothing on /diagnostics")
    elif topic in page.mapped_topics:
        command.notes.append(f"{topic}: a sensor topic the page maps")
    elif not re.search(r'advertise<[^>]+>\(\s*"' + re.escape(base) + '"', page.code):
        command.problems.append(f"{topic}: neither published by the code nor mapped by the "
                                "page's roslaunch lines")


def is_frame(name):
    return bool(re.fullmatch(r"[A-Za-z_<][\w<>/-]*", name)) and not name.startswith("/")


def check_rosrun(page, command, words, rosrun_available):
    if len(words) < 3:
        command.problems.append("rosrun needs a package and an executable")
        return
    package, executable, arguments = words[1], words[2], words[3:]
    if package == PACKAGE:
        cmake = (page.root / "CMakeLists.txt").read_text()
        if not re.search(r"add_executable\(\s*" + re.escape(executable) + r"\b", cmake):
            command.problems.append(f"CMakeLists.txt builds no executable '{executable}'")
    elif rosrun_available:
        environment = ros_environment(page)
        found = False
        libexec = subprocess.run(["catkin_find", "--libexec", package], env=environment,
                                 capture_output=True, text=True)
        folders = libexec.stdout.split()
        share = subprocess.run(["rospack", "find", package], env=environment,
                               capture_output=True, text=True)
        if share.returncode == 0:
            folders.append(share.stdout.strip())
        for folder in folders:
            for path in pathlib.Path(folder).rglob(executable):
                found = found or (path.is_file() and os.access(path, os.X_OK))
        if not found:
            command.problems.append(f"rosrun finds no executable '{executable}' in package "
                                    f"'{package}'")
        else:
            command.notes.append(f"{package}/{executable} found")
    else:
        command.notes.append(f"{package}/{executable} not looked up: no ROS installed")
    positional = [word for word in arguments if not word.startswith("-")]
    if executable == "static_transform_publisher":
        if len(positional) not in (8, 9):
            command.problems.append("static_transform_publisher takes x y z yaw pitch roll (or "
                                    "qx qy qz qw) and two frames")
        else:
            numbers, frames = positional[:-2], positional[-2:]
            try:
                [float(number) for number in numbers]
            except ValueError:
                command.problems.append(f"not numbers: {numbers}")
            if not all(is_frame(frame) for frame in frames) or frames[0] == frames[1]:
                command.problems.append(f"frames {frames}: two names without a leading slash")
    if executable == "echo.py":
        if len(positional) != 2 or not all(is_frame(frame) for frame in positional):
            command.problems.append("echo.py takes two frames without a leading slash")


def check_rviz(page, command, words):
    if len(words) != 3 or words[1] != "-d":
        command.problems.append("only 'rviz -d <file>' is checked")
    elif not pathlib.Path(words[2]).is_file():
        command.problems.append(f"no file {words[2]}")


def expand_globs(page, command, words):
    expanded = []
    for word in words:
        if any(character in word for character in "*?["):
            matches = sorted(glob.glob(word))
            if not matches:
                command.problems.append(f"'{word}' matches no file")
            expanded += matches
        else:
            expanded.append(word)
    return expanded


def run_in_sandbox(page, command, words):
    """cp, mkdir -p and sed -i, on the sandbox only."""
    program = words[0]
    script = None
    if program == "sed":
        scripts = [word for word in words[1:] if not word.startswith("-")]
        if "-i" not in words[1:] or not scripts:
            command.problems.append("only 'sed -i <script> <files>' is checked")
            return
        script = scripts[0]
        at = words.index(script)
        words = words[:at + 1] + expand_globs(page, command, words[at + 1:])
    else:
        words = expand_globs(page, command, words)
    paths = [word for word in words[1:] if not word.startswith("-") and word != script]
    if program == "sed":
        writes = paths
    elif program == "cp":
        writes = paths[-1:]
        for source in paths[:-1]:
            if not (page.inside(source, page.root) or page.inside(source, page.sandbox)):
                command.problems.append(f"copies from outside the package: {source}")
    else:  # mkdir
        writes = paths
    for path in writes:
        if not page.inside(path, page.sandbox):
            command.problems.append(f"writes outside $HOME: {path}")
    if command.problems:
        return
    before = {}
    if program == "sed":
        before = {path: pathlib.Path(path).read_text() for path in writes}
    completed = subprocess.run(words, cwd=page.sandbox, env=ros_environment(page),
                               capture_output=True, text=True)
    if completed.returncode != 0:
        command.problems.append(f"exits {completed.returncode}: {completed.stderr.strip()}")
        return
    if program == "sed":
        changed = [path for path in writes if pathlib.Path(path).read_text() != before[path]]
        if not changed:
            command.problems.append("changes no file")
        key = re.match(r"s(.)\^(\w+):", script)
        if key:
            missed = [pathlib.Path(path).name for path in writes
                      if re.search(r"^" + key.group(2) + r":", before[path], re.M)
                      and path not in changed]
            if missed:
                command.problems.append(f"'{key.group(2)}' left unchanged in {missed}")
        command.notes.append(f"changed {len(changed)} of {len(writes)} files: " +
                             ", ".join(sorted(pathlib.Path(path).name for path in changed)))


def check_page(root, roslaunch):
    text = (root / PAGE).read_text(encoding="utf-8")
    commands = extract_commands(text)
    rosrun_available = shutil.which("rospack") is not None and roslaunch is not None
    with tempfile.TemporaryDirectory(prefix="robot_commands_") as folder:
        page = Page(root, pathlib.Path(folder))
        page.read_keys = parameters_read_in_code(root)
        last_dump = None
        for command in commands:
            words = page.words(command)
            if not words:
                continue
            program = words[0]
            if program == "roslaunch":
                path = check_roslaunch(page, command, words)
                if path is None:
                    continue
                if roslaunch is None:
                    continue
                problems, notes, last_dump = dump_params(page, words, roslaunch)
                command.ros_check = (problems, notes)
            elif program == "rosservice":
                check_rosservice(page, command, words)
            elif program == "rosparam":
                check_rosparam(page, command, words, last_dump)
            elif program == "rostopic":
                check_rostopic(page, command, words)
            elif program == "rosrun":
                check_rosrun(page, command, words, rosrun_available)
            elif program == "rviz":
                check_rviz(page, command, words)
            elif program in ("cp", "sed") or (program == "mkdir" and "-p" in words):
                run_in_sandbox(page, command, words)
            else:
                command.problems.append(f"no check for '{program}' commands: add one to this "
                                        "script or leave the command off the page")
    return commands


def write_junit(path, commands, roslaunch, extraction_problems):
    cases = [("extraction", extraction_problems, None)]
    for command in commands:
        name = f"line {command.line}: {command.text[:100]}"
        cases.append((name, command.problems, None))
        if command.text.startswith("roslaunch"):
            if roslaunch is None:
                cases.append((f"line {command.line}: roslaunch --dump-params", [],
                              "roslaunch not on PATH"))
            elif command.ros_check is not None:
                cases.append((f"line {command.line}: roslaunch --dump-params",
                              command.ros_check[0], None))
    junit_report.write_suite(path, "robot_commands", cases)


def main():
    root, junit = junit_report.check_arguments(__doc__)
    roslaunch = shutil.which("roslaunch")
    commands = check_page(root, roslaunch)
    failed = 0
    for command in commands:
        problems = list(command.problems)
        if command.ros_check is not None:
            problems += command.ros_check[0]
        failed += bool(problems)
        print(f"{PAGE}:{command.line}: {'FAIL' if problems else 'ok'}: {command.text}")
        for problem in problems:
            print(f"    problem: {problem}")
        notes = command.notes + (command.ros_check[1] if command.ros_check else [])
        for note in notes:
            print(f"    {note}")
    if roslaunch is None:
        print("roslaunch is not on PATH: the roslaunch --dump-params checks were skipped "
              "(source the devel space to run them)")
    launches = sum(1 for command in commands if command.text.startswith("roslaunch"))
    extraction_problems = [] if launches else [f"no roslaunch line found in {PAGE}"]
    for problem in extraction_problems:
        print(f"extraction broken: {problem}")
    print(f"{len(commands)} commands ({launches} roslaunch), {failed} failed")
    if junit:
        write_junit(junit, commands, roslaunch, extraction_problems)
    return 1 if failed or extraction_problems else 0


if __name__ == "__main__":
    sys.exit(main())
