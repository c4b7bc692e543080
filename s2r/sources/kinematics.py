"""The kinematic tree of a description: the pose of one link in another through their common parent.

Fixed joints use their ``<origin>``; movable joints are evaluated at position zero (callers warn).
A link with two parent joints, or a chain of joints that comes back to where it started, is a joint
loop and is refused with the joints named.
"""

from __future__ import annotations

import numpy as np

from s2r.errors import SourceError
from s2r.geometry import invert_transform
from s2r.sources.description import Description, FloatArray, JointSpec

__all__ = ["KinematicTree"]


def _where(joint: JointSpec) -> str:
    return f"<joint name={joint.name!r}>" + (f" line {joint.line}" if joint.line else "")


class KinematicTree:
    """Parent joints of every link of ``description``, checked for loops on construction."""

    def __init__(self, description: Description) -> None:
        self.path = description.path
        self.parent_joint: dict[str, JointSpec] = {}
        for joint in description.joints:
            if joint.parent == joint.child:
                self._loop([joint])
            other = self.parent_joint.get(joint.child)
            if other is not None:
                raise SourceError(
                    f"joint loop: link {joint.child!r} is the child of both {other.name!r} and {joint.name!r}",
                    path=self.path, field=_where(joint),
                    hint="a URDF is a tree: give each link one parent joint (remove or re-parent one of them)",
                )
            self.parent_joint[joint.child] = joint
        for link in description.links:
            self.chain_to_root(link)

    def _loop(self, joints: list[JointSpec]) -> None:
        names = " -> ".join(repr(j.name) for j in joints)
        first = joints[0]
        raise SourceError(f"joint loop: {names} comes back to link {first.child!r}", path=self.path,
                          field=_where(first),
                          hint="a URDF is a tree: break the loop by re-parenting one joint")

    def chain_to_root(self, link: str) -> list[JointSpec]:
        """Joints from ``link`` up to its tree's root (first: the link's own parent joint)."""
        chain: list[JointSpec] = []
        seen = {link}
        current = link
        while current in self.parent_joint:
            joint = self.parent_joint[current]
            chain.append(joint)
            if joint.parent in seen:
                self._loop(chain)
            seen.add(joint.parent)
            current = joint.parent
        return chain

    def root_of(self, link: str) -> str:
        """The root link of the tree holding ``link``."""
        chain = self.chain_to_root(link)
        return chain[-1].parent if chain else link

    def pose_in_root(self, link: str) -> tuple[FloatArray, list[JointSpec]]:
        """``T_root_link`` (metres) with movable joints at zero, and the joints on the way."""
        T = np.eye(4)
        chain = self.chain_to_root(link)
        for joint in reversed(chain):
            T = T @ joint.T_parent_child
        return T, chain

    def transform(self, frame_a: str, frame_b: str) -> tuple[FloatArray, list[JointSpec]]:
        """``T_a_b``: pose of link ``frame_b`` in link ``frame_a``, and the movable joints on the path.

        Raises:
            SourceError: the two links are in separate trees (no common parent).
        """
        if self.root_of(frame_a) != self.root_of(frame_b):
            raise SourceError(f"links {frame_a!r} and {frame_b!r} share no common parent", path=self.path,
                              field="<joint>", hint="connect both camera links to one robot with joints")
        T_root_a, chain_a = self.pose_in_root(frame_a)
        T_root_b, chain_b = self.pose_in_root(frame_b)
        common = {j.name for j in chain_a} & {j.name for j in chain_b}
        path = [j for j in chain_a + chain_b if j.name not in common]
        return invert_transform(T_root_a) @ T_root_b, [j for j in path if j.movable]
