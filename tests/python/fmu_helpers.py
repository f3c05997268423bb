"""Low-level access to an FMU with fmpy's FMU2Slave, with the log messages collected."""
import collections
import ctypes
import html.parser
import pathlib
import re
import shutil
import tempfile
import zipfile

from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2CallbackAllocateMemoryTYPE
from fmpy.fmi2 import fmi2CallbackFreeMemoryTYPE

_libc = ctypes.CDLL(None)
_libc.calloc.restype = ctypes.c_void_p
_libc.calloc.argtypes = [ctypes.c_size_t, ctypes.c_size_t]
_libc.free.argtypes = [ctypes.c_void_p]


# What fmi2DoStep logs in the logSolver category: the internal steps, right-hand sides, Jacobian
# evaluations and restarts of CVODE over the communication step.
_SOLVER_LINE = re.compile(r"(\d+) internal steps, (\d+) right-hand sides, (\d+) Jacobians, (\d+) restarts")
SolverReport = collections.namedtuple("SolverReport", "steps rhs jacobians restarts")


class Instance:
    """An instantiated FMU: .slave (FMU2Slave), .vr[name], .messages [(status, category, text)]."""

    def __init__(self, fmu, name="instance", guid=None, unzipdir=None, logging_on=False, instantiate=True):
        self.md = read_model_description(str(fmu))
        self.own_dir = unzipdir is None
        self.unzipdir = unzipdir or extract(str(fmu), unzipdir=tempfile.mkdtemp(prefix="smfmu-"))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.messages = []
        self.slave = FMU2Slave(guid=guid or self.md.guid, unzipDirectory=self.unzipdir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(_libc.calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(_libc.free)
        if instantiate:
            self.slave.instantiate(callbacks=self.callbacks, loggingOn=logging_on)

    def _log(self, env, name, status, category, message):
        self.messages.append((status, category.decode(), message.decode()))

    def log_text(self):
        return "\n".join(m[2] for m in self.messages)

    def solver_reports(self):
        """The solver statistics of each communication step so far, from the logSolver messages
        (the category must be on): [SolverReport(steps, rhs, jacobians, restarts)]."""
        return [SolverReport(*map(int, m.groups())) for _, category, text in self.messages
                if category == "logSolver" and (m := _SOLVER_LINE.search(text))]

    def start(self, start_values=None, start_time=0.0, stop_time=None):
        s = self.slave
        s.setupExperiment(startTime=start_time, stopTime=stop_time)
        s.enterInitializationMode()
        for name, value in (start_values or {}).items():
            self.set(name, value)
        s.exitInitializationMode()
        return self

    def set(self, name, value):
        v = self.variables[name]
        if v.type == "Real":
            self.slave.setReal([v.valueReference], [float(value)])
        elif v.type == "Integer":
            self.slave.setInteger([v.valueReference], [int(value)])
        elif v.type == "Boolean":
            self.slave.setBoolean([v.valueReference], [bool(value)])
        else:
            self.slave.setString([v.valueReference], [value])

    def get(self, *names):
        values = self.slave.getReal([self.vr[n] for n in names])
        return values[0] if len(names) == 1 else values

    def free(self):
        """Frees the instance, if there is one, and unloads the FMU's library once: fmpy's
        freeInstance unloads it itself, and a second unload would drop a reference that another
        Instance of the same unzipped FMU holds."""
        try:
            if self.slave.component:
                self.slave.freeInstance()
            else:
                self.slave.freeLibrary()
        finally:
            if self.own_dir:
                shutil.rmtree(self.unzipdir, ignore_errors=True)


def springmass_version():
    """MAJOR.MINOR.PATCH, as include/springmass/base.h defines it."""
    root = pathlib.Path(__file__).resolve().parents[2]
    text = (root / "include" / "springmass" / "base.h").read_text()
    return ".".join(re.search(rf"#define SM_VERSION_{part} (\d+)", text).group(1)
                    for part in ("MAJOR", "MINOR", "PATCH"))


def fmu_guid(model, parameters=None):
    """The GUID of an FMU's resources (fmu/fmu_model.h, fmu_package_guid): the 128-bit FNV-1a hash
    of "springmass MAJOR.MINOR.PATCH" and a NUL byte, continued over resources/model.json's bytes,
    and over a NUL byte and resources/parameters.txt's bytes when the FMU has that file."""
    data = f"springmass {springmass_version()}\0".encode() + model
    data = data if parameters is None else data + b"\0" + parameters
    h = 0x6c62272e07bb014262b821756295c58d
    for byte in data:
        h = ((h ^ byte) * 0x0000000001000000000000000000013b) & ((1 << 128) - 1)
    x = f"{h:032x}"
    return "{%s-%s-%s-%s-%s}" % (x[:8], x[8:12], x[12:16], x[16:20], x[20:])


class FmuDocumentation(html.parser.HTMLParser):
    """documentation/index.html of an FMU, read back: .title, .paragraphs {section: [text]},
    .tables {section: [[cell text]]} (the header row left out) and .links [href]; a section is
    named by its h2's id ("" before the first)."""

    def __init__(self, text):
        super().__init__(convert_charrefs=True)
        self.title, self.section = "", ""
        self.paragraphs, self.tables, self.links = {}, {}, []
        self._in, self._text, self._row = None, [], None
        self.feed(text)
        self.close()

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "h2":
            self.section = attrs.get("id", "")
        elif tag in ("title", "p", "td", "th"):
            self._in, self._text = tag, []
        elif tag == "tr":
            self._row = []
        elif tag == "a":
            self.links.append(attrs.get("href"))

    def handle_endtag(self, tag):
        text = "".join(self._text)
        if tag == "title":
            self.title = text
        elif tag == "p":
            self.paragraphs.setdefault(self.section, []).append(text)
        elif tag == "td":
            self._row.append(text)
        elif tag == "tr" and self._row:
            self.tables.setdefault(self.section, []).append(self._row)
        if tag == self._in:
            self._in = None

    def handle_data(self, data):
        if self._in:
            self._text.append(data)


def read_documentation(fmu):
    """The FmuDocumentation of the FMU file's documentation/index.html."""
    with zipfile.ZipFile(fmu) as archive:
        return FmuDocumentation(archive.read("documentation/index.html").decode("utf-8"))
