"""primlabel: the Python client of the primlabel point labeling service, and PCD and PLY files
to numpy (primlabel.read picks the reader by the extension).

    import primlabel
    with primlabel.Client("127.0.0.1:50051") as client:
        cloud = primlabel.pcd.read("scan.pcd")
        result = client.label(cloud.xyz, viewpoint=cloud.viewpoint[:3])
        cloud.label = result.labels
        primlabel.pcd.write("scan_labeled.pcd", cloud)
"""

from . import pcd, ply
from ._version import __version__
from .backoff import Backoff, BackoffPolicy
from .client import ClassInfo, Client, HealthStatus, Result, Tls, probability_field_name
from .errors import DomainWarning, InvalidInput, PrimlabelError
from .files import UnsupportedFormat, read
from .wire import NO_OBJECT, NO_SEGMENT

__all__ = [
    "Backoff",
    "BackoffPolicy",
    "ClassInfo",
    "DomainWarning",
    "Client",
    "HealthStatus",
    "InvalidInput",
    "NO_OBJECT",
    "NO_SEGMENT",
    "PrimlabelError",
    "Result",
    "Tls",
    "UnsupportedFormat",
    "__version__",
    "pcd",
    "ply",
    "probability_field_name",
    "read",
]
