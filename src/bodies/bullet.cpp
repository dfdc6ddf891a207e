// The thin C wrapper around Bullet (libbullet-dev) that the bodies module uses for what Bullet does well: the
// rigid-body state, gravity, and contacts between bodies and with the tank's walls (tall cells Sec. 4.4 uses
// BulletPhysics the same way). Every rank runs the same world with the same inputs, so every rank holds the same
// bodies. Only this file includes Bullet.
#include "bullet.h"

#include <btBulletDynamicsCommon.h>
#include <new>
#include <vector>

struct PffBulletWorld {
  btDefaultCollisionConfiguration     config;
  btCollisionDispatcher               dispatcher{&config};
  btDbvtBroadphase                    broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld             world{&dispatcher, &broadphase, &solver, &config};
  std::vector<btCollisionShape *>     shapes;
  std::vector<btDefaultMotionState *> states;
  std::vector<btRigidBody *>          bodies; // walls first, then the user's bodies
  int                                 nwalls = 0;
};

extern "C" PffBulletWorld *PffBulletCreate(const double gravity[3], const double lo[3], const double hi[3])
{
  PffBulletWorld *w = new (std::nothrow) PffBulletWorld;
  if (!w) return nullptr;
  w->world.setGravity(btVector3(gravity[0], gravity[1], gravity[2]));
  // the six walls: static planes facing into the tank
  for (int a = 0; a < 3; a++)
    for (int side = 0; side < 2; side++) {
      btVector3 n(0, 0, 0);
      n[a]                                            = side ? -1 : 1;
      const double                             offset = side ? -hi[a] : lo[a];
      btCollisionShape                        *plane  = new btStaticPlaneShape(n, offset);
      btDefaultMotionState                    *ms     = new btDefaultMotionState(btTransform::getIdentity());
      btRigidBody::btRigidBodyConstructionInfo info(0, ms, plane, btVector3(0, 0, 0));
      btRigidBody                             *body = new btRigidBody(info);
      w->world.addRigidBody(body);
      w->shapes.push_back(plane);
      w->states.push_back(ms);
      w->bodies.push_back(body);
      w->nwalls++;
    }
  return w;
}

extern "C" int PffBulletAddBody(PffBulletWorld *w, int type, const double size[3], double mass, const double x[3],
                                double inertia[3])
{
  btCollisionShape *shape;
  if (type == PFF_BULLET_BOX)
    shape = new btBoxShape(btVector3(size[0], size[1], size[2]));
  else
    shape = new btSphereShape(size[0]);
  btVector3 local(0, 0, 0);
  shape->calculateLocalInertia(mass, local);
  btTransform start = btTransform::getIdentity();
  start.setOrigin(btVector3(x[0], x[1], x[2]));
  btDefaultMotionState                    *ms = new btDefaultMotionState(start);
  btRigidBody::btRigidBodyConstructionInfo info(mass, ms, shape, local);
  btRigidBody                             *body = new btRigidBody(info);
  body->setActivationState(DISABLE_DEACTIVATION); // the liquid moves it; Bullet must not put it to sleep
  w->world.addRigidBody(body);
  w->shapes.push_back(shape);
  w->states.push_back(ms);
  w->bodies.push_back(body);
  for (int a = 0; a < 3; a++) inertia[a] = local[a];
  return (int)w->bodies.size() - w->nwalls - 1;
}

extern "C" void PffBulletStep(PffBulletWorld *w, double dt)
{
  w->world.stepSimulation(dt, 0); // one step of exactly dt (no fixed sub-steps: the flow sets it)
}

extern "C" void PffBulletGetState(const PffBulletWorld *w, int i, double x[3], double q[4], double v[3],
                                  double omega[3])
{
  const btRigidBody *b = w->bodies[w->nwalls + i];
  const btTransform &t = b->getCenterOfMassTransform();
  const btQuaternion r = t.getRotation();
  for (int a = 0; a < 3; a++) {
    x[a]     = t.getOrigin()[a];
    v[a]     = b->getLinearVelocity()[a];
    omega[a] = b->getAngularVelocity()[a];
  }
  q[0] = r.getW();
  q[1] = r.getX();
  q[2] = r.getY();
  q[3] = r.getZ();
}

extern "C" void PffBulletSetVelocity(PffBulletWorld *w, int i, const double v[3], const double omega[3])
{
  btRigidBody *b = w->bodies[w->nwalls + i];
  b->setLinearVelocity(btVector3(v[0], v[1], v[2]));
  b->setAngularVelocity(btVector3(omega[0], omega[1], omega[2]));
}

extern "C" void PffBulletGetRaw(const PffBulletWorld *w, int i, double s[PFF_BULLET_RAW])
{
  const btRigidBody *b = w->bodies[w->nwalls + i];
  const btTransform &t = b->getCenterOfMassTransform();
  for (int a = 0; a < 3; a++) {
    s[a]      = t.getOrigin()[a];
    s[12 + a] = b->getLinearVelocity()[a];
    s[15 + a] = b->getAngularVelocity()[a];
    for (int c = 0; c < 3; c++) s[3 + 3 * a + c] = t.getBasis()[a][c];
  }
}

extern "C" void PffBulletSetRaw(PffBulletWorld *w, int i, const double s[PFF_BULLET_RAW])
{
  btRigidBody *b = w->bodies[w->nwalls + i];
  btMatrix3x3  basis(s[3], s[4], s[5], s[6], s[7], s[8], s[9], s[10], s[11]);
  btTransform  t(basis, btVector3(s[0], s[1], s[2]));
  b->setCenterOfMassTransform(t);
  b->getMotionState()->setWorldTransform(t);
  b->setLinearVelocity(btVector3(s[12], s[13], s[14]));
  b->setAngularVelocity(btVector3(s[15], s[16], s[17]));
  b->updateInertiaTensor();
}

extern "C" void PffBulletDestroy(PffBulletWorld *w)
{
  if (!w) return;
  for (btRigidBody *b : w->bodies) w->world.removeRigidBody(b);
  for (btRigidBody *b : w->bodies) delete b;
  for (btDefaultMotionState *m : w->states) delete m;
  for (btCollisionShape *s : w->shapes) delete s;
  delete w;
}
