"""primlabel: the Python client of the primlabel point labeling service, and PCD and PLY files
to numpy (primlabel.read picks the reader by the extension).

    import primlabel
    with primlabel.Client("127.0.0.1:50051") as client:
        cloud = primlabel.read("scan.pcd")  # or .ply
        result = client.label(cloud)  # or the path, an (N, 3) array, an Open3D cloud
        cloud.label = result.labels
        print(result.classes[result.labels[0]].name)  # every label's class, 0 "unknown" too
        primlabel.pcd.write("scan_labeled.pcd", cloud)
"""

from . import instances, pcd, ply
from ._version import __version__
from .backoff import Backoff, BackoffPolicy
from .client import (
    UNKNOWN_CLASS,
    ClassInfo,
    Client,
    HealthStatus,
    Result,
    Tls,
    probability_field_name,
)
from .errors import DomainWarning, InvalidInput, PrimlabelError
from .files import UnsupportedFormat, read
from .instances import (
    Cylinder,
    Line,
    Plane,
    Primitive,
    Sphere,
    TabletopObject,
    TabletopTable,
    Torus,
)
from .wire import NO_OBJECT, NO_SEGMENT

__all__ = [
    "Backoff",
    "BackoffPolicy",
    "ClassInfo",
    "Client",
    "Cylinder",
    "DomainWarning",
    "HealthStatus",
    "InvalidInput",
    "Line",
    "NO_OBJECT",
    "NO_SEGMENT",
    "Plane",
    "Primitive",
    "PrimlabelError",
    "Result",
    "Sphere",
    "TabletopObject",
    "TabletopTable",
    "Tls",
    "Torus",
    "UNKNOWN_CLASS",
    "UnsupportedFormat",
    "__version__",
    "instances",
    "pcd",
    "ply",
    "probability_field_name",
    "read",
]
