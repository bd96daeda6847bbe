/* carom's harness around Box2D v3 (C): its benchmark pyramids, timed step by step.
 *
 *   pyramid large <seconds> <workers> [trace]
 *   pyramid many <seconds> <workers>
 *
 * "large": Box2D's large pyramid (100 rows of unit boxes, density 1, friction 0.6, on a
 * 200 m x 2 m ground), built here with the body order kept so that the top box is known;
 * "many": Box2D's own CreateManyPyramids (400 pyramids of 10 rows on 20 shelves, from its
 * shared/benchmarks.c). Both with sleep off, Box2D's default world (continuous on), stepped at
 * 60 Hz with 4 substeps on `workers` threads of Box2D's own scheduler (1: the calling thread
 * only). Every step is timed, the first too (as carom's are); between two steps only Box2D's
 * own profile is read (a copy of a few floats), and with `trace` the top box's pose.
 *
 * Prints one line of `name value` pairs: ms_per_step, the sums of Box2D's own profile
 * (collide_ms, solve_ms per step), and for the large pyramid the top box's move, the largest
 * turn of any box at the end [deg] and the largest speed at the end [m/s]. With `trace` it
 * first prints the top box's `t x y angle` after every step (reading it between steps, so a
 * traced run is not a timed one). benchmarks/steppers.py builds and runs it.
 */
#define _POSIX_C_SOURCE 199309L
#include "benchmarks.h"
#include "box2d/box2d.h"
#include "box2d/math_functions.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now_seconds( void )
{
	struct timespec t;
	clock_gettime( CLOCK_MONOTONIC, &t );
	return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* the large pyramid, boxes in Box2D's order (row by row from the ground; the last is the top) */
static b2BodyId* large_pyramid( b2WorldId world, int rows, int* count )
{
	b2BodyDef groundDef = b2DefaultBodyDef();
	groundDef.position.y = -1.0f;
	b2BodyId ground = b2CreateBody( world, &groundDef );
	b2ShapeDef groundShape = b2DefaultShapeDef();
	b2Polygon slab = b2MakeBox( 100.0f, 1.0f );
	b2CreatePolygonShape( ground, &groundShape, &slab );

	*count = rows * ( rows + 1 ) / 2;
	b2BodyId* boxes = malloc( sizeof( b2BodyId ) * (size_t)*count );
	b2ShapeDef boxShape = b2DefaultShapeDef();
	boxShape.density = 1.0f;
	b2Polygon square = b2MakeSquare( 0.5f );
	int n = 0;
	for ( int row = 0; row < rows; ++row )
	{
		for ( int k = 0; k < rows - row; ++k )
		{
			b2BodyDef def = b2DefaultBodyDef();
			def.type = b2_dynamicBody;
			def.position.x = ( row + 1.0f ) * 0.5f + (float)k - 0.5f * (float)rows;
			def.position.y = row + 0.5f;
			boxes[n] = b2CreateBody( world, &def );
			b2CreatePolygonShape( boxes[n], &boxShape, &square );
			++n;
		}
	}
	return boxes;
}

int main( int argc, char** argv )
{
	if ( argc < 4 || ( strcmp( argv[1], "large" ) != 0 && strcmp( argv[1], "many" ) != 0 ) )
	{
		fprintf( stderr, "usage: pyramid large|many <seconds> <workers> [trace]\n" );
		return 2;
	}
	int large = strcmp( argv[1], "large" ) == 0;
	int steps = (int)lround( atof( argv[2] ) * 60.0 );
	int workers = atoi( argv[3] );
	int trace = argc > 4 && strcmp( argv[4], "trace" ) == 0;

	b2WorldDef worldDef = b2DefaultWorldDef();
	worldDef.enableSleep = false;
	worldDef.workerCount = workers;
	b2WorldId world = b2CreateWorld( &worldDef );
	int count = 0;
	b2BodyId* boxes = NULL;
	if ( large )
	{
		boxes = large_pyramid( world, 100, &count );
	}
	else
	{
		CreateManyPyramids( world );
	}

	double wall = 0.0, collide = 0.0, solve = 0.0;
	for ( int s = 0; s < steps; ++s )
	{
		double began = now_seconds();
		b2World_Step( world, 1.0f / 60.0f, 4 );
		wall += now_seconds() - began;
		b2Profile profile = b2World_GetProfile( world );
		collide += profile.collide;
		solve += profile.solve;
		if ( trace && large )
		{
			b2Pos p = b2Body_GetPosition( boxes[count - 1] );
			double angle = b2Rot_GetAngle( b2Body_GetRotation( boxes[count - 1] ) );
			printf( "%.6f %.9g %.9g %.9g\n", ( s + 1 ) / 60.0, (double)p.x, (double)p.y, angle );
		}
	}

	printf( "ms_per_step %.5f collide_ms %.5f solve_ms %.5f", 1e3 * wall / steps, collide / steps,
			solve / steps );
	if ( large )
	{
		b2Pos p = b2Body_GetPosition( boxes[count - 1] );
		double x0 = 0.0, y0 = 99.5; /* the top box at the start: row 99, x = 100 * 0.5 - 50 */
		double turn = 0.0, fastest = 0.0;
		for ( int i = 0; i < count; ++i )
		{
			double a = fabs( (double)b2Rot_GetAngle( b2Body_GetRotation( boxes[i] ) ) );
			turn = a > turn ? a : turn;
			b2Vec2 v = b2Body_GetLinearVelocity( boxes[i] );
			double speed = hypot( (double)v.x, (double)v.y );
			fastest = speed > fastest ? speed : fastest;
		}
		printf( " top_moved_m %.6f max_turn_deg %.5f max_speed_m_s %.6g",
				hypot( (double)p.x - x0, (double)p.y - y0 ), turn * 180.0 / 3.14159265358979, fastest );
		free( boxes );
	}
	printf( "\n" );
	b2DestroyWorld( world );
	return 0;
}
