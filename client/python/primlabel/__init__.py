"""primlabel: the Python client of the primlabel point labeling service, and PCD files to numpy.

    import primlabel
    with primlabel.Client("127.0.0.1:50051") as client:
        cloud = primlabel.pcd.read("scan.pcd")
        result = client.label(cloud.xyz, viewpoint=cloud.viewpoint[:3])
        cloud.label = result.labels
        primlabel.pcd.write("scan_labeled.pcd", cloud)
"""

from . import pcd
from ._version import __version__
from .backoff import Backoff, BackoffPolicy
from .client import ClassInfo, Client, HealthStatus, Result, Tls, probability_field_name
from .errors import DomainWarning, InvalidInput, PrimlabelError
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
    "__version__",
    "pcd",
    "probability_field_name",
]
